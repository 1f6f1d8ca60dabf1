// Texture lookup benchmarks (Google Benchmark): the cost of one nearest, bilinear and trilinear
// lookup of MipMap<float> and MipMap<double> on a course texture (hw4's earth.jpg, 1024x512), at
// the same pseudo-random (u, v) points (and, for trilinear, levels spread over the pyramid), with
// the texels as the renderer keeps them (the JPEG's bytes, image/texels.hpp) and as floats, side
// by side in one run; and the cost of decoding the file each way (read_texels, read_image).
//
// Each benchmark sums the texels it reads and checks the sum against the same sum computed
// once before timing (per interpolation), so the lookups cannot be optimised away and a wrong
// lookup stops the run. Lookups run one at a time on one thread. See bench/RESULTS.md.
#include <prism/image/image_io.hpp>
#include <prism/texture/mipmap.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <vector>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace {

using namespace prism;

const std::filesystem::path earth =
    std::filesystem::path(PRISM_SHARED_DIR) / "ceng795/hw4/2022F_Batucan2601/hw4/inputs/textures/earth.jpg";

constexpr std::size_t lookups_per_batch = 1 << 16;

// (u, v) in [-0.5, 1.5)^2, so repeat addressing is exercised, and a level in [0, 10].
struct Query {
    double u, v, level;
};

const std::vector<Query>& queries() {
    static const std::vector<Query> batch = [] {
        std::vector<Query> q(lookups_per_batch);
        std::uint64_t state = 0x9E3779B97F4A7C15ull;
        const auto next = [&] {  // splitmix64: fixed, so every run reads the same texels
            state += 0x9E3779B97F4A7C15ull;
            std::uint64_t z = state;
            z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
            z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
            return double((z ^ (z >> 31)) >> 11) / double(1ull << 53);
        };
        for (Query& query : q) query = {next() * 2 - 0.5, next() * 2 - 0.5, next() * 10};
        return q;
    }();
    return batch;
}

// The texels as the renderer keeps them (bytes) or widened to floats.
template <Scalar Real>
const MipMap<Real>& earth_map(bool bytes) {
    static const MipMap<Real> from_bytes(std::make_shared<const Texels>(read_texels(earth)));
    static const MipMap<Real> from_floats(read_image(earth));
    return bytes ? from_bytes : from_floats;
}

template <Scalar Real>
double sum_of_lookups(const MipMap<Real>& map, scene::Interpolation interpolation) {
    Vec3<Real> sum(0);
    for (const Query& q : queries()) sum += map.lookup(Vec2<Real>(Real(q.u), Real(q.v)), Real(q.level), interpolation);
    return double(sum.x + sum.y + sum.z);
}

template <Scalar Real>
void texture_lookup(benchmark::State& state, scene::Interpolation interpolation, bool bytes) {
    if (!std::filesystem::exists(earth)) {
        state.SkipWithError(("course texture not found: " + earth.string()).c_str());
        return;
    }
    const MipMap<Real>& map = earth_map<Real>(bytes);
    const double expected = sum_of_lookups(map, interpolation);
    // Both storages read the same numbers: their sums must agree bit for bit.
    if (expected != sum_of_lookups(earth_map<Real>(!bytes), interpolation)) {
        state.SkipWithError("bytes and floats gave different lookups");
        return;
    }
    for (auto _ : state) {
        const double sum = sum_of_lookups(map, interpolation);
        benchmark::DoNotOptimize(sum);
        if (sum != expected) {
            state.SkipWithError("the lookups' checksum changed between batches");
            return;
        }
    }
    state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(lookups_per_batch));
    state.counters["ns_per_lookup"] = benchmark::Counter(
        double(state.iterations()) * double(lookups_per_batch),
        benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
    state.counters["checksum"] = expected;
}

void build_pyramid(benchmark::State& state) {
    if (!std::filesystem::exists(earth)) {
        state.SkipWithError(("course texture not found: " + earth.string()).c_str());
        return;
    }
    const auto texels = std::make_shared<const Texels>(read_texels(earth));
    for (auto _ : state) {
        MipMap<float> map(texels);
        benchmark::DoNotOptimize(map.levels());
    }
}

// Reading and decoding the file: its bytes kept (what the scene loader does) or widened to floats.
void decode(benchmark::State& state, bool bytes) {
    if (!std::filesystem::exists(earth)) {
        state.SkipWithError(("course texture not found: " + earth.string()).c_str());
        return;
    }
    for (auto _ : state) {
        if (bytes) {
            const Texels texels = read_texels(earth);
            benchmark::DoNotOptimize(texels(texels.width() - 1, texels.height() - 1));
        } else {
            const Image image = read_image(earth);
            benchmark::DoNotOptimize(image(image.width - 1, image.height - 1));
        }
    }
}

}  // namespace

// Google Benchmark's macros take a plain function name, not a template-id.
void lookup_float(benchmark::State& state, prism::scene::Interpolation interpolation, bool bytes) {
    texture_lookup<float>(state, interpolation, bytes);
}
void lookup_double(benchmark::State& state, prism::scene::Interpolation interpolation, bool bytes) {
    texture_lookup<double>(state, interpolation, bytes);
}

BENCHMARK_CAPTURE(lookup_float, nearest_bytes, prism::scene::Interpolation::nearest, true);
BENCHMARK_CAPTURE(lookup_float, nearest_floats, prism::scene::Interpolation::nearest, false);
BENCHMARK_CAPTURE(lookup_float, bilinear_bytes, prism::scene::Interpolation::bilinear, true);
BENCHMARK_CAPTURE(lookup_float, bilinear_floats, prism::scene::Interpolation::bilinear, false);
BENCHMARK_CAPTURE(lookup_float, trilinear_bytes, prism::scene::Interpolation::trilinear, true);
BENCHMARK_CAPTURE(lookup_float, trilinear_floats, prism::scene::Interpolation::trilinear, false);
BENCHMARK_CAPTURE(lookup_double, nearest_bytes, prism::scene::Interpolation::nearest, true);
BENCHMARK_CAPTURE(lookup_double, nearest_floats, prism::scene::Interpolation::nearest, false);
BENCHMARK_CAPTURE(lookup_double, bilinear_bytes, prism::scene::Interpolation::bilinear, true);
BENCHMARK_CAPTURE(lookup_double, bilinear_floats, prism::scene::Interpolation::bilinear, false);
BENCHMARK_CAPTURE(lookup_double, trilinear_bytes, prism::scene::Interpolation::trilinear, true);
BENCHMARK_CAPTURE(lookup_double, trilinear_floats, prism::scene::Interpolation::trilinear, false);
BENCHMARK(build_pyramid)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(decode, bytes, true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(decode, floats, false)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
