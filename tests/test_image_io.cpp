// Image files and image comparison: round trips through PNG and EXR, the shared environment maps
// (tiled and scanline EXR, Radiance HDR), PSNR, the off-pixel share, the box filter, and writes
// that must fail without leaving anything behind.
#include <prism/image/compare.hpp>
#include <prism/image/image_io.hpp>

#include <doctest/doctest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace fs = std::filesystem;

namespace {

// A fresh, empty folder per test case, removed when the case ends.
struct ScratchFolder {
    fs::path path;
    explicit ScratchFolder(const std::string& name)
        : path(fs::temp_directory_path() / ("prism_test_image_io_" + std::to_string(::getpid()) + "_" + name)) {
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~ScratchFolder() {
        std::error_code ignored;
        fs::remove_all(path, ignored);
    }
    std::size_t entry_count() const {
        return std::size_t(std::distance(fs::recursive_directory_iterator(path), fs::recursive_directory_iterator()));
    }
};

fs::path shared_envmap(const char* name) { return fs::path(PRISM_SHARED_DIR) / "envmaps" / name; }

bool all_finite(const prism::Image& image) {
    for (const auto& pixel : image.pixels)
        if (!std::isfinite(pixel.r) || !std::isfinite(pixel.g) || !std::isfinite(pixel.b)) return false;
    return true;
}

prism::Image constant_image(int width, int height, glm::vec3 value) {
    prism::Image image(width, height);
    for (auto& pixel : image.pixels) pixel = value;
    return image;
}

glm::dvec3 mean(const prism::Image& image) {
    glm::dvec3 sum(0.0);
    for (const auto& pixel : image.pixels) sum += glm::dvec3(pixel);
    return sum / double(image.pixels.size());
}

// Noise-like values from a linear congruential stream, -20 .. 321, so that both of the 8-bit
// conversion's clamps are taken and deflate's matches cross rows.
prism::Image noise_image(int width, int height, std::uint32_t state) {
    prism::Image image(width, height);
    for (auto& pixel : image.pixels)
        for (int c = 0; c < 3; ++c) {
            state = state * 1664525u + 1013904223u;
            pixel[c] = float(state >> 20) / 12.0f - 20.0f;
        }
    return image;
}

// A file's bytes, as written.
std::vector<std::uint8_t> file_bytes(const fs::path& path) {
    std::ifstream stream(path, std::ios::binary);
    return std::vector<std::uint8_t>((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
}

// An encoder's file of `image` at 1 and at 2 threads (encode: encode_png or encode_exr).
template <class Encode>
std::vector<std::vector<std::uint8_t>> encoded_at_1_and_2_threads(const prism::Image& image, Encode encode) {
    std::vector<std::vector<std::uint8_t>> files;
    for (int threads : {1, 2}) {
        const tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
        const std::optional<std::vector<std::uint8_t>> file = encode(image);
        REQUIRE(file.has_value());
        files.push_back(*file);
    }
    return files;
}

}  // namespace

TEST_CASE("to_8bit clamps to 0..255 and truncates, as the course does") {
    prism::Image image(4, 2);
    const float values[8] = {-5.0f, 0.49999997f, 0.5f, 1.49f, 127.5f, 254.6f, 255.0f, 1e9f};
    const std::uint8_t expected[8] = {0, 0, 0, 1, 127, 254, 255, 255};
    for (int i = 0; i < 8; ++i) image.pixels[std::size_t(i)] = glm::vec3(values[i]);
    image.pixels[0].g = std::numeric_limits<float>::quiet_NaN();
    const auto bytes = prism::to_8bit(image);
    REQUIRE(bytes.size() == 24);
    for (int i = 0; i < 8; ++i) CHECK(int(bytes[std::size_t(3 * i + 2)]) == int(expected[i]));
    CHECK(bytes[1] == 0);  // NaN is black
}

TEST_CASE("PNG and PPM round trips hold exactly the to_8bit values") {
    for (const char* name : {"round_trip.PNG", "round_trip.ppm"}) {  // upper case: extensions are case-blind
        CAPTURE(name);
        ScratchFolder folder("8bit");
        prism::Image image(7, 5);  // odd width: rows are not 4-byte aligned
        for (int y = 0; y < image.height; ++y)
            for (int x = 0; x < image.width; ++x)
                image(x, y) = glm::vec3(float(x) * 40.3f - 20.0f, float(y) * 70.7f, float(x * y) * 9.5f + 0.5f);
        const fs::path file = folder.path / "nested" / name;  // the missing folder is created
        prism::write_image(file, image);
        const prism::Image read = prism::read_image(file);
        REQUIRE(read.width == image.width);
        REQUIRE(read.height == image.height);
        const auto expected = prism::to_8bit(image);
        CHECK(prism::to_8bit(read) == expected);
        for (std::size_t i = 0; i < read.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c) CHECK(read.pixels[i][c] == float(expected[3 * i + std::size_t(c)]));
        CHECK(folder.entry_count() == 2);  // the folder and the file: no temporary left behind
    }
}

TEST_CASE("the film is black when made, small or in huge pages, and copies whole") {
    for (const int side : {3, 1024}) {  // 108 bytes, and 12 MB: FilmAllocator's huge-page path
        CAPTURE(side);
        prism::Image image(side, side);
        REQUIRE(image.pixels.size() == std::size_t(side) * std::size_t(side));
        std::size_t lit = 0;
        for (const auto& pixel : image.pixels) lit += pixel != glm::vec3(0.0f);
        CHECK(lit == 0);
        image.pixels.back() = glm::vec3(1.0f, 2.0f, 3.0f);
        const prism::Image copy = image;
        CHECK(copy.pixels == image.pixels);
        prism::Image unfilled(side, 2, prism::Image::Unfilled{});
        CHECK(unfilled.pixels.size() == std::size_t(side) * 2);
    }
}

TEST_CASE("a PPM of many row blocks and a PNG decoded in runs hold the to_8bit values") {
    // 1024 x 768: PPM rows of 3,072 bytes, so write_ppm's 64 kB blocks hold 21 rows and the image
    // takes 37 of them, the last one short; decode_image converts its 786,432 pixels in runs.
    const prism::Image image = noise_image(1024, 768, 777u);
    const auto expected = prism::to_8bit(image);
    ScratchFolder folder("blocks");
    const fs::path ppm = folder.path / "blocks.ppm";
    prism::write_image(ppm, image);
    const std::vector<std::uint8_t> written = file_bytes(ppm);
    const std::string header = "P6\n1024 768\n255\n";
    REQUIRE(written.size() == header.size() + expected.size());
    CHECK(std::equal(header.begin(), header.end(), written.begin()));
    CHECK(std::equal(expected.begin(), expected.end(), written.begin() + std::ptrdiff_t(header.size())));
    for (const char* name : {"blocks.ppm", "blocks.png"}) {
        CAPTURE(name);
        if (std::string(name) == "blocks.png") prism::write_image(folder.path / name, image);
        for (int threads : {1, 2}) {
            const tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
            const prism::Image read = prism::read_image(folder.path / name);
            REQUIRE(read.pixels.size() == image.pixels.size());
            bool same = true;
            for (std::size_t i = 0; i < read.pixels.size(); ++i)
                for (int c = 0; c < 3; ++c) same = same && read.pixels[i][c] == float(expected[3 * i + std::size_t(c)]);
            CHECK(same);
        }
    }
}

TEST_CASE("a PNG of many bands decodes to the to_8bit values, in the same bytes at 1 and 2 threads") {
    // 601 x 500: rows of 1,803 bytes, so png_band_rows gives 54 rows a band and ten bands, the
    // last one short.
    const prism::Image image = noise_image(601, 500, 12345u);
    REQUIRE(prism::detail::png_band_rows(601 * 3) < image.height / 4);
    const auto files = encoded_at_1_and_2_threads(image, [](const prism::Image& i) { return prism::encode_png(i); });
    CHECK(files[0] == files[1]);
    ScratchFolder folder("bands");
    const fs::path path = folder.path / "bands.png";
    prism::write_image(path, image);
    CHECK(file_bytes(path) == files[0]);
    const prism::Image read = prism::read_image(path);
    REQUIRE(read.width == image.width);
    REQUIRE(read.height == image.height);
    CHECK(prism::to_8bit(read) == prism::to_8bit(image));
}

TEST_CASE("EXR round trip is bit-identical, in B,G,R channel order") {
    ScratchFolder folder("exr");
    prism::Image image(19, 17);  // larger than 16x16, so the ZIP-compressed path is taken
    const float specials[] = {0.0f, 1.0f, 255.0f, 1e6f, 3.4e38f, 1e-30f, 1e-40f /* subnormal */,
                              -2.5f, 0.1f, 1.0f / 3.0f};
    std::size_t n = 0;
    for (auto& pixel : image.pixels) {
        pixel = glm::vec3(specials[n % 10], specials[(n + 3) % 10] * 1.5f, float(n) * 0.0123f);
        ++n;
    }
    image.pixels[0] = glm::vec3(1.0f, 2.0f, 3.0f);  // distinct channels: a swapped order shows
    const fs::path file = folder.path / "round_trip.exr";
    prism::write_image(file, image);
    const prism::Image read = prism::read_image(file);
    REQUIRE(read.width == image.width);
    REQUIRE(read.height == image.height);
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            if (std::memcmp(&read.pixels[i][c], &image.pixels[i][c], sizeof(float)) != 0) ++mismatches;
    CHECK(mismatches == 0);
    CHECK(read.pixels[0] == glm::vec3(1.0f, 2.0f, 3.0f));

    EXRVersion version;
    REQUIRE(ParseEXRVersionFromFile(&version, file.c_str()) == TINYEXR_SUCCESS);
    EXRHeader header;
    InitEXRHeader(&header);
    const char* error = nullptr;
    REQUIRE(ParseEXRHeaderFromFile(&header, &version, file.c_str(), &error) == TINYEXR_SUCCESS);
    REQUIRE(header.num_channels == 3);
    CHECK(std::string(header.channels[0].name) == "B");
    CHECK(std::string(header.channels[1].name) == "G");
    CHECK(std::string(header.channels[2].name) == "R");
    for (int c = 0; c < 3; ++c) CHECK(header.pixel_types[c] == TINYEXR_PIXELTYPE_FLOAT);
    FreeEXRHeader(&header);
}

namespace {

// Bits of every kind a float can hold, from a 32-bit LCG's high bits: NaNs with payloads,
// infinities, subnormals, -0; incompressible, so deflate cannot shrink their blocks.
prism::Image random_bits_image(int width, int height, std::uint32_t state) {
    prism::Image image(width, height);
    for (auto& pixel : image.pixels)
        for (int c = 0; c < 3; ++c) {
            std::uint32_t bits = 0;
            for (int half = 0; half < 2; ++half) {
                state = state * 1664525u + 1013904223u;
                bits = (bits << 16) | (state >> 16);
            }
            std::memcpy(&pixel[c], &bits, sizeof(float));
        }
    return image;
}

std::size_t bit_mismatches(const prism::Image& a, const prism::Image& b) {
    if (a.width != b.width || a.height != b.height) return std::size_t(-1);
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            if (std::memcmp(&a.pixels[i][c], &b.pixels[i][c], sizeof(float)) != 0) ++mismatches;
    return mismatches;
}

}  // namespace

TEST_CASE("encode_exr: tinyexr reads back every float's bits, from the same bytes at 1 and 2 threads") {
    ScratchFolder folder("exr_blocks");
    // Heights around the 16-row block (a short last block, a single row); widths of one pixel
    // and of an odd number.
    const std::pair<int, int> sizes[] = {{1, 1}, {1, 40}, {601, 16}, {33, 17}, {601, 500}, {7, 15}};
    for (const auto& size : sizes) {
        const int width = size.first, height = size.second;
        for (bool noise : {false, true}) {
            CAPTURE(width);
            CAPTURE(height);
            CAPTURE(noise);
            // Renders' values (smooth and rounded, which deflate shrinks) or random bits (which it
            // cannot: those blocks are stored as they are).
            const prism::Image image = noise ? random_bits_image(width, height, 99u + std::uint32_t(width))
                                             : noise_image(width, height, 7u + std::uint32_t(height));
            const auto files =
                encoded_at_1_and_2_threads(image, [](const prism::Image& i) { return prism::encode_exr(i); });
            CHECK(files[0] == files[1]);
            const std::size_t raw_bytes = image.pixels.size() * 12;
            // Random bits are stored as they are, behind the header and the offsets; noise_image
            // repeats its 4,096 values, which deflate shrinks where there are many pixels.
            if (noise) CHECK(files[0].size() > raw_bytes);
            else if (raw_bytes > 8192) CHECK(files[0].size() < raw_bytes);
            const fs::path path = folder.path / "blocks.exr";
            prism::write_image(path, image);
            CHECK(file_bytes(path) == files[0]);
            CHECK(bit_mismatches(prism::read_image(path), image) == 0);
        }
    }
}

TEST_CASE("the shared environment maps read: tiled and scanline EXR, Radiance HDR") {
    if (!fs::is_directory(fs::path(PRISM_SHARED_DIR) / "envmaps")) {
        MESSAGE("skipped: " PRISM_SHARED_DIR "/envmaps not found");
        return;
    }
    for (const char* name : {"KernerEnvLatLong.exr", "pbrtv2_grace_latlong.exr"}) {
        CAPTURE(name);
        const prism::Image image = prism::read_image(shared_envmap(name));
        CHECK(image.width == 1024);
        CHECK(image.height == 512);
        CHECK(all_finite(image));
        CHECK(mean(image).g > 0.0);  // a map of zeros would mean the channels were not found
    }
    const prism::Image hdr = prism::read_image(shared_envmap("probulator_grace_latlong.hdr"));
    CHECK(hdr.width == 256);
    CHECK(hdr.height == 128);
    CHECK(all_finite(hdr));
    CHECK(mean(hdr).g > 0.0);
}

TEST_CASE("reading a missing or unknown file names the file") {
    ScratchFolder folder("read_errors");
    const fs::path missing = folder.path / "missing.png";
    CHECK_THROWS_WITH_AS(prism::read_image(missing), doctest::Contains("missing.png"), prism::io::LoadError);
    const fs::path text = folder.path / "not_an_image.png";
    std::ofstream(text) << "hello";
    CHECK_THROWS_WITH_AS(prism::read_image(text), doctest::Contains("not_an_image.png"), prism::io::LoadError);
    const fs::path broken_exr = folder.path / "broken.exr";
    std::ofstream(broken_exr) << "v/1\x01 not really";
    CHECK_THROWS_WITH_AS(prism::read_image(broken_exr), doctest::Contains("broken.exr"), prism::io::LoadError);
}

TEST_CASE("psnr against a hand-computed value") {
    const std::vector<std::uint8_t> a = {10, 20, 30, 40, 50, 60};
    const std::vector<std::uint8_t> b = {12, 20, 30, 40, 50, 57};
    // squared errors 4 + 9 = 13 over 6 values: 10 log10(255^2 * 6 / 13)
    CHECK(prism::psnr(a, b) == doctest::Approx(44.77288258944717).epsilon(1e-12));
    CHECK(prism::psnr(a, a) == std::numeric_limits<double>::infinity());
    CHECK_THROWS_AS(prism::psnr(a, {1, 2, 3}), std::invalid_argument);
}

TEST_CASE("share_off_by_more_than counts pixels, not channels") {
    // four pixels: equal; off by exactly 8 (not more); off by 9 in one channel; off by 9 in all
    const std::vector<std::uint8_t> a = {0, 0, 0, 100, 100, 100, 50, 50, 50, 200, 200, 200};
    const std::vector<std::uint8_t> b = {0, 0, 0, 108, 92, 100, 50, 59, 50, 191, 209, 191};
    CHECK(prism::share_off_by_more_than(a, b, 8) == doctest::Approx(0.5));
    CHECK(prism::share_off_by_more_than(a, b, 7) == doctest::Approx(0.75));
    CHECK(prism::share_off_by_more_than(a, b, 9) == 0.0);
    CHECK(prism::share_off_by_more_than(a, a, 0) == 0.0);
}

TEST_CASE("downsample_box averages by area") {
    SUBCASE("a constant image stays constant") {
        const prism::Image reduced = prism::downsample_box(constant_image(13, 7, {3.0f, 100.0f, 0.25f}), 5, 3);
        REQUIRE(reduced.width == 5);
        REQUIRE(reduced.height == 3);
        for (const auto& pixel : reduced.pixels) {
            CHECK(pixel.r == doctest::Approx(3.0));
            CHECK(pixel.g == doctest::Approx(100.0));
            CHECK(pixel.b == doctest::Approx(0.25));
        }
    }
    SUBCASE("a 4x4 checker to 2x2 gives each quadrant's average") {
        prism::Image checker(4, 4);
        for (int y = 0; y < 4; ++y)
            for (int x = 0; x < 4; ++x) checker(x, y) = glm::vec3(float((x + y) % 2) * 255.0f, float(x + 4 * y), 0.0f);
        const prism::Image reduced = prism::downsample_box(checker, 2, 2);
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 2; ++x) {
                CHECK(reduced(x, y).r == doctest::Approx(127.5));
                // green: the mean of x + 4y over the quadrant's four pixels
                const double expected = (2 * x + 0.5) + 4.0 * (2 * y + 0.5);
                CHECK(reduced(x, y).g == doctest::Approx(expected));
            }
    }
    SUBCASE("a non-integer ratio (5x5 to 2x2) preserves the mean and weights partial pixels") {
        prism::Image ramp(5, 5);
        for (int y = 0; y < 5; ++y)
            for (int x = 0; x < 5; ++x) ramp(x, y) = glm::vec3(float(x), float(y * y), float(x * 7 + y));
        const prism::Image reduced = prism::downsample_box(ramp, 2, 2);
        const glm::dvec3 before = mean(ramp), after = mean(reduced);
        for (int c = 0; c < 3; ++c) CHECK(after[c] == doctest::Approx(before[c]).epsilon(1e-6));
        // left half covers x in [0, 2.5): (0 + 1 + 0.5 * 2) / 2.5
        CHECK(reduced(0, 0).r == doctest::Approx(0.8));
        CHECK(reduced(1, 0).r == doctest::Approx((0.5 * 2 + 3 + 4) / 2.5));
    }
}

TEST_CASE("write_image fails whole: no partial file, nothing behind") {
    ScratchFolder folder("write_errors");
    const prism::Image image = constant_image(3, 2, {10.0f, 20.0f, 30.0f});

    SUBCASE("a folder that cannot be created (under a regular file)") {
        std::ofstream(folder.path / "plain_file") << "x";
        CHECK_THROWS_AS(prism::write_image(folder.path / "plain_file" / "sub" / "out.png", image), prism::io::LoadError);
        CHECK_THROWS_AS(prism::write_image(folder.path / "plain_file" / "out.exr", image), prism::io::LoadError);
        CHECK(folder.entry_count() == 1);
    }
    SUBCASE("the target is a folder: the temporary file is removed") {
        fs::create_directories(folder.path / "taken.png");
        CHECK_THROWS_AS(prism::write_image(folder.path / "taken.png", image), prism::io::LoadError);
        CHECK(folder.entry_count() == 1);
    }
    SUBCASE("an unknown extension") {
        CHECK_THROWS_WITH_AS(prism::write_image(folder.path / "out.tiff", image), doctest::Contains("ImageName"),
                             prism::io::LoadError);
        CHECK_THROWS_AS(prism::write_image(folder.path / "no_extension", image), prism::io::LoadError);
        CHECK(folder.entry_count() == 0);
    }
    SUBCASE("an existing file is replaced whole") {
        const fs::path file = folder.path / "replace.png";
        prism::write_image(file, constant_image(5, 5, {1.0f, 2.0f, 3.0f}));
        prism::write_image(file, image);
        const prism::Image read = prism::read_image(file);
        CHECK(read.width == 3);
        CHECK(read.pixels[0] == glm::vec3(10.0f, 20.0f, 30.0f));
        CHECK(folder.entry_count() == 1);
    }
}
