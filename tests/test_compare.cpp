// RMSE over 8-bit images (image/compare.hpp): the error the speed-against-accuracy chart plots
// next to the share of off pixels, and its agreement with PSNR, which is computed from the same
// mean square. The functions take 8-bit bytes, not a Real, so there is no float/double pair.
#include <prism/image/compare.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

TEST_CASE("rmse: zero for identical images, in 8-bit levels otherwise") {
    const std::vector<std::uint8_t> a{10, 20, 30, 40, 50, 60};
    CHECK(prism::rmse(a, a) == 0.0);

    // One channel of six off by 6 levels: sqrt(36 / 6).
    std::vector<std::uint8_t> b = a;
    b[4] = 56;
    CHECK(prism::rmse(a, b) == doctest::Approx(std::sqrt(6.0)).epsilon(1e-15));
    CHECK(prism::rmse(b, a) == prism::rmse(a, b));

    // Every channel off by 3 levels, in either direction: exactly 3.
    const std::vector<std::uint8_t> c{13, 17, 33, 37, 53, 57};
    CHECK(prism::rmse(a, c) == doctest::Approx(3.0).epsilon(1e-15));

    // The extremes: black against white is 255.
    CHECK(prism::rmse(std::vector<std::uint8_t>(6, 0), std::vector<std::uint8_t>(6, 255)) == 255.0);
}

TEST_CASE("rmse and psnr come from the same mean square: psnr = 20 log10(255 / rmse)") {
    const std::vector<std::uint8_t> a{0, 64, 128, 192, 255, 7, 9, 200, 100};
    const std::vector<std::uint8_t> b{3, 60, 128, 190, 250, 7, 12, 201, 90};
    CHECK(prism::psnr(a, b) == doctest::Approx(20.0 * std::log10(255.0 / prism::rmse(a, b))).epsilon(1e-12));
}

TEST_CASE("rmse refuses images of different sizes and empty images") {
    CHECK_THROWS_AS(prism::rmse({1, 2, 3}, {1, 2, 3, 4, 5, 6}), std::invalid_argument);
    CHECK_THROWS_AS(prism::rmse({}, {}), std::invalid_argument);
}

TEST_CASE("display_8bit and mean_grey_exposure: one exposure from the reference, gamma-encoded, clamped") {
    prism::Image reference(2, 1);
    reference(0, 0) = glm::vec3(0.1f);
    reference(1, 0) = glm::vec3(0.26f);
    // Mean luminance 0.18: the exposure is 1 (luminance weights sum to 1).
    CHECK(prism::mean_grey_exposure(reference) == doctest::Approx(1.0).epsilon(1e-6));
    const std::vector<std::uint8_t> bytes = prism::display_8bit(reference, 2.0);
    REQUIRE(bytes.size() == 6);
    CHECK(int(bytes[0]) == int(std::lround(255 * std::pow(0.2, 1 / 2.2))));
    CHECK(int(bytes[3]) == int(std::lround(255 * std::pow(0.52, 1 / 2.2))));
    CHECK(int(prism::display_8bit(reference, 10.0)[3]) == 255);  // clamped
    prism::Image black(1, 1);
    CHECK(prism::mean_grey_exposure(black) == 1.0);
    // Doubling the reference's radiance halves the exposure: the display is the same.
    prism::Image brighter = reference;
    for (auto& pixel : brighter.pixels) pixel *= 2.0f;
    CHECK(prism::display_8bit(brighter, prism::mean_grey_exposure(brighter)) ==
          prism::display_8bit(reference, prism::mean_grey_exposure(reference)));
}
