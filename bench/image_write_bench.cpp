// What writing a render's images costs (Google Benchmark): an EXR by prism's encoder
// (image/exr_encoder.hpp) and by tinyexr's SaveEXRImageToMemory as prism called it before (three
// FLOAT channels B, G, R, ZIP, zlib's default level, one thread), and a tone map
// (image/tonemap.hpp), at 1 and 2 threads, on films from ../shared: two path-traced course
// references and a photographed environment map.
//
// Before timing, each encoding is decoded by tinyexr and compared with the film bit for bit, and
// the run stops on a difference. The file's size is reported as the counter `bytes`. See
// bench/RESULTS.md, "Writing the images".
#include <prism/image/image_io.hpp>
#include <prism/image/tonemap.hpp>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace {

using namespace prism;

struct Film {
    const char* name;
    const char* path;  // under PRISM_SHARED_DIR
};

const Film films[] = {
    {"path_diffuse_next", "ceng795/hw7_pathtracing_objlights/expected/2022F_Batucan2601/diffuse_next.exr"},
    {"VeachAjar_path", "ceng795/hw7_pathtracing_objlights/expected/2022F_Batucan2601/VeachAjar_path.exr"},
    {"KernerEnvLatLong", "envmaps/KernerEnvLatLong.exr"},
};

const Image& film(std::size_t index) {
    static std::vector<Image> images(std::size(films));
    if (images[index].pixels.empty())
        images[index] = read_image(std::filesystem::path(PRISM_SHARED_DIR) / films[index].path);
    return images[index];
}

std::vector<std::uint8_t> tinyexr_encoding(const Image& image) {
    const std::size_t count = image.pixels.size();
    std::vector<float> red(count), green(count), blue(count);
    for (std::size_t i = 0; i < count; ++i) {
        red[i] = image.pixels[i].r;
        green[i] = image.pixels[i].g;
        blue[i] = image.pixels[i].b;
    }
    float* planes[3] = {blue.data(), green.data(), red.data()};
    EXRImage exr_image;
    InitEXRImage(&exr_image);
    exr_image.num_channels = 3;
    exr_image.images = reinterpret_cast<unsigned char**>(planes);
    exr_image.width = image.width;
    exr_image.height = image.height;
    EXRChannelInfo channels[3] = {};
    const char names[3] = {'B', 'G', 'R'};
    for (int c = 0; c < 3; ++c) {
        channels[c].name[0] = names[c];
        channels[c].x_sampling = channels[c].y_sampling = 1;
    }
    int pixel_types[3] = {TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT};
    EXRHeader header;
    InitEXRHeader(&header);
    header.num_channels = 3;
    header.channels = channels;
    header.pixel_types = pixel_types;
    header.requested_pixel_types = pixel_types;
    header.compression_type = TINYEXR_COMPRESSIONTYPE_ZIP;
    unsigned char* memory = nullptr;
    const char* error = nullptr;
    const std::size_t size = SaveEXRImageToMemory(&exr_image, &header, &memory, &error);
    std::vector<std::uint8_t> file(memory, memory + size);
    std::free(memory);
    if (error) FreeEXRErrorMessage(error);
    return file;
}

std::vector<std::uint8_t> prism_encoding(const Image& image) { return encode_exr(image).value_or(std::vector<std::uint8_t>{}); }

// The encoding decoded again must be the film, bit for bit.
void check_round_trip(const std::vector<std::uint8_t>& file, const Image& image, const char* what) {
    const Image read =
        decode_image(std::string_view(reinterpret_cast<const char*>(file.data()), file.size()),
                     std::filesystem::path(std::string(what) + ".exr"));
    if (read.width != image.width || read.height != image.height ||
        std::memcmp(read.pixels.data(), image.pixels.data(), image.pixels.size() * sizeof(glm::vec3)) != 0) {
        std::fprintf(stderr, "image_write_bench: %s does not read back as the film\n", what);
        std::exit(1);
    }
}

template <std::vector<std::uint8_t> (*Encode)(const Image&)>
void encode(benchmark::State& state) {
    const Image& image = film(std::size_t(state.range(0)));
    const tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
    std::vector<std::uint8_t> file = Encode(image);
    check_round_trip(file, image, films[state.range(0)].name);
    for (auto _ : state) {
        file = Encode(image);
        benchmark::DoNotOptimize(file.data());
    }
    state.counters["bytes"] = double(file.size());
    state.SetLabel(films[state.range(0)].name);
}

void tone_map_film(benchmark::State& state) {
    const Image& image = film(std::size_t(state.range(0)));
    const tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
    scene::Tonemap settings;  // the course's usual Photographic key 0.18, burn 1, gamma 2.2
    settings.burn_percent = 1;
    for (auto _ : state) {
        const Image mapped = tone_map(image, settings);
        benchmark::DoNotOptimize(mapped.pixels.data());
    }
    state.SetLabel(films[state.range(0)].name);
}

void films_and_threads(benchmark::internal::Benchmark* b) {
    for (int f = 0; f < int(std::size(films)); ++f)
        for (int threads : {1, 2}) b->Args({f, threads});
    b->Unit(benchmark::kMillisecond)->UseRealTime();
}

BENCHMARK(encode<prism_encoding>)->Name("exr/prism")->Apply(films_and_threads);
BENCHMARK(encode<tinyexr_encoding>)->Name("exr/tinyexr")->Apply(films_and_threads);
BENCHMARK(tone_map_film)->Name("tone_map")->Apply(films_and_threads);

}  // namespace

BENCHMARK_MAIN();
