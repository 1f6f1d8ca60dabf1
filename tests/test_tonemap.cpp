// Tone mapping (image/tonemap.hpp): each curve and the whole Photographic pipeline against values
// worked out by hand from the equations, ACES and Filmic against their published curves, the
// names of the images a camera writes, and the course's own EXR/PNG pairs.
#include <prism/image/compare.hpp>
#include <prism/image/image_io.hpp>
#include <prism/image/tonemap.hpp>

#include <doctest/doctest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace {

namespace fs = std::filesystem;
using prism::Image;
using prism::scene::Tonemap;
using prism::scene::TonemapOperator;

Image grey_image(int width, int height, const std::vector<float>& values) {
    Image image(width, height);
    for (std::size_t i = 0; i < values.size(); ++i) image.pixels[i] = glm::vec3(values[i]);
    return image;
}

Tonemap photographic(double key, double burn, double saturation = 1.0, double gamma = 2.2) {
    Tonemap tonemap;
    tonemap.key = key;
    tonemap.burn_percent = burn;
    tonemap.saturation = saturation;
    tonemap.gamma = gamma;
    return tonemap;
}

// Tone-mapped levels agree with the hand values to 1e-4 relative (the float film and delta
// = 1e-6 move them by less than that).
void check_levels(const Image& image, const std::vector<double>& expected_red) {
    REQUIRE(image.pixels.size() == expected_red.size());
    for (std::size_t i = 0; i < expected_red.size(); ++i) {
        CAPTURE(i);
        CHECK(image.pixels[i].r == doctest::Approx(expected_red[i]).epsilon(1e-4));
    }
}

}  // namespace

TEST_CASE_TEMPLATE("luminance uses the Rec. 709 weights", Real, float, double) {
    using V = prism::Vec3<Real>;
    CHECK(prism::luminance(V(1, 0, 0)) == doctest::Approx(0.2126));
    CHECK(prism::luminance(V(0, 1, 0)) == doctest::Approx(0.7152));
    CHECK(prism::luminance(V(0, 0, 1)) == doctest::Approx(0.0722));
    CHECK(prism::luminance(V(2, 2, 2)) == doctest::Approx(2.0));
}

TEST_CASE_TEMPLATE("log-average luminance: exp(mean(log(delta + Y)))", Real, float, double) {
    // 0.5, 1, 2 and 4: the geometric mean is 4^(1/4) = sqrt(2).
    const std::vector<Real> Y{Real(0.5), Real(1), Real(2), Real(4)};
    CHECK(prism::log_average_luminance(Y) == doctest::Approx(std::sqrt(2.0)).epsilon(1e-5));
    // A black pixel counts as log(delta): with delta 1e-6, {0, 1} averages to sqrt(1e-6) = 1e-3.
    const std::vector<Real> with_black{Real(0), Real(1)};
    CHECK(prism::log_average_luminance(with_black) == doctest::Approx(1e-3).epsilon(1e-5));
    CHECK(prism::log_average_luminance(with_black, Real(1e-4)) == doctest::Approx(1e-2).epsilon(1e-4));
}

TEST_CASE_TEMPLATE("Photographic curve: L/(1+L) without burn, L(1+L/Lw^2)/(1+L) with", Real, float, double) {
    const Real none = prism::infinity<Real>;
    CHECK(prism::photographic_curve(Real(1), none) == doctest::Approx(0.5));
    CHECK(prism::photographic_curve(Real(0.18), none) == doctest::Approx(0.18 / 1.18));
    // At L = L_white the curve reaches exactly 1: that pixel just burns out.
    CHECK(prism::photographic_curve(Real(3), Real(3)) == doctest::Approx(1.0));
    CHECK(prism::photographic_curve(Real(1), Real(2)) == doctest::Approx(1.0 * 1.25 / 2.0));
}

TEST_CASE_TEMPLATE("L_white is the scaled luminance at the (100 - burn) percentile", Real, float, double) {
    std::vector<Real> values;
    for (int i = 100; i >= 1; --i) values.push_back(Real(i));  // order must not matter
    CHECK(std::isinf(prism::white_luminance(values, Real(0))));
    CHECK(prism::white_luminance(values, Real(1)) == Real(100));   // element floor(100 * 0.99) = 99
    CHECK(prism::white_luminance(values, Real(10)) == Real(91));   // element 90
    CHECK(prism::white_luminance(values, Real(100)) == Real(1));   // everything burns
    CHECK(prism::white_luminance(std::vector<Real>{Real(5)}, Real(50)) == Real(5));
}

TEST_CASE_TEMPLATE("Photographic tone mapping of a whole image, by hand: key, burn, saturation, gamma", Real, float,
                   double) {
    // Grey pixels 0.5, 1, 2, 4: L_avg = sqrt(2), L = 0.18 / sqrt(2) * Y = 0.1272792 Y.
    const Image image = grey_image(2, 2, {0.5f, 1.0f, 2.0f, 4.0f});

    SUBCASE("burn 0: L/(1+L), then 255 Ld^(1/2.2)") {
        // Ld = 0.0598319, 0.1129083, 0.2029068, 0.3373608.
        check_levels(prism::tone_map<Real>(image, photographic(0.18, 0)), {70.89256, 94.61524, 123.50229, 155.61008});
    }
    SUBCASE("burn 25%: L_white is the brightest pixel's L (element floor(4 * 0.75) = 3), which maps to white") {
        // L_white = 0.5091169; Ld = 0.0745221, 0.1683516, 0.4021801, 1.
        check_levels(prism::tone_map<Real>(image, photographic(0.18, 25)), {78.33257, 113.45423, 168.55101, 255.0});
    }
    SUBCASE("burn 50%: the two brightest burn out") {
        // L_white = 0.2545584; Ld = 0.1185924, 0.3346813, 1, 2.99 (clamped).
        check_levels(prism::tone_map<Real>(image, photographic(0.18, 50)), {96.75134, 155.04706, 255.0, 255.0});
    }
    SUBCASE("the key scales the exposure") {
        // Key 0.72 is four times 0.18: L = 0.5091169 Y, so the pixel Y = 1 gets Ld = L / (1 + L) = 0.3373608.
        const Image mapped = prism::tone_map<Real>(image, photographic(0.72, 0));
        CHECK(mapped.pixels[1].r == doctest::Approx(155.61008).epsilon(1e-4));
    }
    SUBCASE("gamma 1 leaves 255 Ld") {
        check_levels(prism::tone_map<Real>(image, photographic(0.18, 0, 1.0, 1.0)),
                     {255 * 0.0598319, 255 * 0.1129083, 255 * 0.2029068, 255 * 0.3373608});
    }
}

TEST_CASE_TEMPLATE("Photographic colour: (C / Y)^saturation * Ld per channel", Real, float, double) {
    // One pixel (0.8, 0.4, 0.2): Y = 0.4706, the image's own average, so L = key and Ld = 0.18 / 1.18.
    Image image(1, 1);
    image.pixels[0] = {0.8f, 0.4f, 0.2f};
    const auto check_pixel = [&](double saturation, double gamma, const glm::dvec3& expected) {
        CAPTURE(saturation);
        CAPTURE(gamma);
        const glm::vec3 mapped = prism::tone_map<Real>(image, photographic(0.18, 0, saturation, gamma)).pixels[0];
        for (int c = 0; c < 3; ++c) CHECK(mapped[c] == doctest::Approx(expected[c]).epsilon(1e-4));
    };
    // 255 (C / 0.4706) * 0.1525424: ratios 1.699957, 0.849979, 0.424989.
    check_pixel(1.0, 1.0, {66.12547, 33.06273, 16.53137});
    // Square roots of the ratios: 1.303824, 0.921943, 0.651912.
    check_pixel(0.5, 1.0, {50.71655, 35.86202, 25.35828});
    // Saturation 0 is grey at the mapped luminance.
    check_pixel(0.0, 1.0, {38.89831, 38.89831, 38.89831});
    check_pixel(1.0, 2.2, {138.06978, 100.75505, 73.52499});
}

TEST_CASE_TEMPLATE("black, broken and empty images", Real, float, double) {
    Image image = grey_image(2, 1, {0.0f, 1.0f});
    const Image mapped = prism::tone_map<Real>(image, photographic(0.18, 1));
    CHECK(mapped.pixels[0] == glm::vec3(0.0f));
    CHECK(mapped.pixels[1].r > 0.0f);
    // A NaN pixel shows black and leaves the others as they would be with a black pixel there.
    image.pixels[0] = glm::vec3(std::numeric_limits<float>::quiet_NaN());
    const Image with_nan = prism::tone_map<Real>(image, photographic(0.18, 1));
    CHECK(with_nan.pixels[0] == glm::vec3(0.0f));
    CHECK(with_nan.pixels[1] == mapped.pixels[1]);
    CHECK(prism::tone_map<Real>(Image{}, photographic(0.18, 1)).pixels.empty());
}

TEST_CASE_TEMPLATE("a tone map is the same image at 1 and 2 threads, for every curve", Real, float, double) {
    // 700 x 300: more than two of tone_map_grain's runs, so two threads share every pass.
    Image hdr(700, 300);
    REQUIRE(hdr.pixels.size() > 4 * prism::tone_map_grain);
    std::uint32_t state = 2024u;
    for (auto& pixel : hdr.pixels)
        for (int c = 0; c < 3; ++c) {
            state = state * 1664525u + 1013904223u;
            pixel[c] = std::ldexp(float(state >> 8), -20) * float(1 + (state & 7));  // 0 to ~128
        }
    hdr.pixels[5] = glm::vec3(-1.0f, std::numeric_limits<float>::quiet_NaN(), 2.0f);  // a broken pixel
    for (const TonemapOperator tone_operator :
         {TonemapOperator::photographic, TonemapOperator::aces, TonemapOperator::filmic}) {
        for (const double saturation : {1.0, 0.6}) {
            Tonemap settings;
            settings.tone_operator = tone_operator;
            settings.key = 0.18;
            settings.burn_percent = 1;
            settings.saturation = saturation;
            settings.gamma = 2.2;
            std::vector<Image> images;
            for (int threads : {1, 2}) {
                const tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
                images.push_back(prism::tone_map<Real>(hdr, settings));
            }
            CAPTURE(saturation);
            CHECK(std::memcmp(images[0].pixels.data(), images[1].pixels.data(), images[0].pixels.size() * sizeof(glm::vec3)) == 0);
            CHECK(images[0].pixels[5] == glm::vec3(0.0f, 0.0f, 0.0f));
        }
    }
}

TEST_CASE_TEMPLATE("ACES: Narkowicz's fitted curve", Real, float, double) {
    CHECK(prism::aces_curve(Real(0)) == Real(0));
    CHECK(prism::aces_curve(Real(1)) == doctest::Approx(0.8038).epsilon(1e-4));  // 2.54 / 3.16
    CHECK(prism::aces_curve(Real(0.18)) == doctest::Approx(0.266899).epsilon(1e-5));
    CHECK(prism::aces_curve(Real(2)) == doctest::Approx(0.914855).epsilon(1e-5));
    CHECK(prism::aces_curve(Real(1e6)) == doctest::Approx(2.51 / 2.43).epsilon(1e-4));  // its asymptote, clamped later
    // Through the pipeline: one grey pixel is its own average, so L = key = 0.18.
    Tonemap tonemap = photographic(0.18, 0, 1.0, 1.0);
    tonemap.tone_operator = TonemapOperator::aces;
    CHECK(prism::tone_map<Real>(grey_image(1, 1, {3.0f}), tonemap).pixels[0].g == doctest::Approx(255 * 0.266899).epsilon(1e-4));
}

TEST_CASE_TEMPLATE("Filmic: Hable's Uncharted 2 curve over its value at W = 11.2", Real, float, double) {
    // h(x) = (x(0.15x + 0.05) + 0.004) / (x(0.15x + 0.5) + 0.06) - 0.02/0.30; h(11.2) = 19.38 / 24.476 - 1/15 = 0.725129.
    // h(1) = 0.204 / 0.71 - 1/15 = 0.220657, so filmic(1) = 0.304301.
    CHECK(prism::filmic_curve(Real(0)) == doctest::Approx(0.0).epsilon(1e-6));
    CHECK(prism::filmic_curve(Real(1)) == doctest::Approx(0.304301).epsilon(1e-5));
    CHECK(prism::filmic_curve(Real(0.18)) == doctest::Approx(0.0671098).epsilon(1e-4));
    CHECK(prism::filmic_curve(Real(2)) == doctest::Approx(0.492919).epsilon(1e-5));
    CHECK(prism::filmic_curve(Real(11.2)) == doctest::Approx(1.0));
    Tonemap tonemap = photographic(0.18, 0, 1.0, 2.2);
    tonemap.tone_operator = TonemapOperator::filmic;
    CHECK(prism::tone_map<Real>(grey_image(1, 1, {3.0f}), tonemap).pixels[0].b == doctest::Approx(74.68977).epsilon(1e-4));
}

TEST_CASE("the images a camera writes") {
    prism::scene::Camera camera;
    camera.image_name = "out/cube.exr";
    CHECK(prism::camera_outputs(camera).size() == 1);

    Tonemap aces;
    aces.tone_operator = TonemapOperator::aces;
    aces.extension = "_aces.png";
    Tonemap filmic;
    filmic.tone_operator = TonemapOperator::filmic;
    filmic.extension = "_filmic";  // no file type: .png is added
    camera.tonemaps = {Tonemap{}, aces, filmic};
    std::vector<prism::CameraOutput> outputs = prism::camera_outputs(camera);
    REQUIRE(outputs.size() == 4);
    CHECK(outputs[0].name == fs::path("out/cube.exr"));
    CHECK(!outputs[0].tonemap);
    CHECK(outputs[1].name == fs::path("out/cube.png"));  // no Extension: the stem + .png
    CHECK(outputs[1].tonemap == 0u);
    CHECK(outputs[2].name == fs::path("out/cube_aces.png"));
    CHECK(outputs[2].tonemap == 1u);
    CHECK(outputs[3].name == fs::path("out/cube_filmic.png"));
    // An Extension that is only a file type replaces the .exr: not "cube.png.png".
    Tonemap plain;
    plain.extension = ".png";
    CHECK(prism::tone_mapped_image_name("out/cube.exr", plain) == fs::path("out/cube.png"));

    // A .png image name with Tonemaps is itself tone-mapped: by the one without Extension...
    camera.image_name = "cube.png";
    outputs = prism::camera_outputs(camera);
    REQUIRE(outputs.size() == 3);
    CHECK(outputs[0].name == fs::path("cube.png"));
    CHECK(outputs[0].tonemap == 0u);
    // ... or, when each names its own file, by the first.
    camera.tonemaps = {aces, filmic};
    outputs = prism::camera_outputs(camera);
    REQUIRE(outputs.size() == 3);
    CHECK(outputs[0].name == fs::path("cube.png"));
    CHECK(outputs[0].tonemap == 0u);
    CHECK(outputs[1].name == fs::path("cube_aces.png"));
}

// The only tone-mapped references the course data holds are EXR/PNG pairs shipped side by side
// (hw6, hw7; [medium]): tone-mapping the EXR must give the PNG. They settle the conventions the
// equations leave open (luminance weights, delta, rounding): see tonemap.hpp.
TEST_CASE_TEMPLATE("the course's EXR/PNG pairs: the EXR tone-mapped is the PNG", Real, float, double) {
    const fs::path expected = fs::path(PRISM_SHARED_DIR) / "ceng795";
    struct Pair {
        const char* exr;
        double key, burn;
    };
    const Pair pairs[] = {
        // Burn 1%, 7.8% black pixels: sensitive to delta.
        {"hw6/expected/2022F_Batucan2601/cornellbox_jaroslav_diffuse.exr", 0.18, 1},
        // Burn 0: the L/(1+L) curve; sensitive to the luminance weights.
        {"hw7_pathtracing_objlights/expected/2022F_Batucan2601/VeachAjar_path.exr", 0.20, 0},
    };
    for (const Pair& pair : pairs) {
        const fs::path exr = expected / pair.exr;
        fs::path png = exr;
        png.replace_extension(".png");
        if (!fs::exists(exr) || !fs::exists(png)) {
            MESSAGE("skipped: " << exr.string() << " not found");
            continue;
        }
        CAPTURE(exr.string());
        const Image mapped = prism::tone_map<Real>(prism::read_image(exr), photographic(pair.key, pair.burn));
        const double psnr = prism::psnr(prism::to_8bit(mapped), prism::to_8bit(prism::read_image(png)));
        MESSAGE(exr.filename().string() << ": " << psnr << " dB");
        CHECK(psnr >= 60.0);
    }
}
