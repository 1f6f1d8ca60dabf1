// Whether a path tracer's rays gain by going through the query seam in batches (issue 29): the
// bounce rays and shadow rays of paths in two hw7 path-traced scenes, traced one by one and in
// batches of 16 through SceneGeometry's one closest-hit and one any-hit entry, whose index then
// takes its route (SceneIndex::route(): leaf lanes in the Cornell box, whose world meshes' root
// holds a few leaves; index lanes in VeachAjar). The rays are what a path's bounces send: from
// points on the surfaces (where random rays from inside the scene first hit), in directions
// uniform over the sphere, and towards points near the scene's top (a light). Neither set is
// coherent, unlike a row's camera rays or its shadow rays to one point light, which the ray
// tracer batches.
//
//   prism_seam_bench [--rays N] [--runs N]
//
// Per scene and query: the time a ray, one by one and in batches, the minimum and the median of
// --runs passes over the same rays, and their ratio. Checks every answer: each ray's batch hit is
// its hit alone, to the bit (t, object, primitive, barycentrics), and each shadow ray's answer
// the same; stops with an error otherwise. One thread, wall clock.
#include <prism/geometry/scene_geometry.hpp>
#include <prism/io/load.hpp>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace {

namespace fs = std::filesystem;
using Real = float;
using Geometry = prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>;
using Vec3 = prism::Vec3<Real>;
using Clock = std::chrono::steady_clock;

const fs::path hw7 = fs::path(PRISM_SHARED_DIR) / "ceng795/hw7_pathtracing_objlights/2022F_Batucan2601/hw6";

struct Rays {
    std::vector<prism::Ray<Real>> bounce, shadow;
};

// Bounce rays leave the first surface a random ray from inside the scene's middle meets; shadow
// rays go from there to a point near the top of the scene's box, stopping short of it.
Rays make_rays(const Geometry& geometry, int count) {
    std::mt19937 random(7);
    std::uniform_real_distribution<Real> uniform(0, 1);
    const auto direction = [&] {
        const Real z = 1 - 2 * uniform(random), phi = 2 * prism::pi<Real> * uniform(random);
        const Real r = std::sqrt(std::max(Real(0), 1 - z * z));
        return Vec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    const prism::Aabb<Real> box = geometry.bounds();
    const Vec3 size = box.max - box.min, middle = (box.min + box.max) * Real(0.5);
    Rays rays;
    while (int(rays.bounce.size()) < count) {
        const Vec3 from = middle + Real(0.6) * (Vec3(uniform(random), uniform(random), uniform(random)) - Real(0.5)) * size;
        prism::Ray<Real> probe{from, direction(), Real(0), prism::infinity<Real>};
        prism::Hit<Real> hit;
        if (!prism::closest_hit(geometry, probe, hit)) continue;
        const Vec3 point = from + probe.direction * (hit.t * Real(0.999));
        rays.bounce.push_back({point, direction(), Real(1e-4), prism::infinity<Real>});
        const Vec3 light = middle + Vec3(size.x * Real(0.2) * (uniform(random) - Real(0.5)), size.y * Real(0.45),
                                         size.z * Real(0.2) * (uniform(random) - Real(0.5)));
        const Vec3 to_light = light - point;
        const Real distance = glm::length(to_light);
        rays.shadow.push_back({point, to_light / distance, Real(1e-4), distance * Real(0.999)});
    }
    return rays;
}

struct Timing {
    std::vector<double> ns;  // a ray, per run
    double min() const { return *std::min_element(ns.begin(), ns.end()); }
    double median() const {
        std::vector<double> sorted = ns;
        std::sort(sorted.begin(), sorted.end());
        return sorted[sorted.size() / 2];
    }
};

template <class Pass>
Timing time_runs(int runs, std::size_t rays, Pass pass) {
    pass();  // warms the caches; untimed
    Timing timing;
    for (int run = 0; run < runs; ++run) {
        const auto start = Clock::now();
        pass();
        timing.ns.push_back(std::chrono::duration<double, std::nano>(Clock::now() - start).count() / double(rays));
    }
    return timing;
}

bool same_hit(const prism::Hit<Real>& a, const prism::Hit<Real>& b) {
    return std::memcmp(&a.t, &b.t, sizeof(Real)) == 0 && a.object == b.object && a.primitive == b.primitive &&
           std::memcmp(&a.b1, &b.b1, sizeof(Real)) == 0 && std::memcmp(&a.b2, &b.b2, sizeof(Real)) == 0;
}

constexpr int batch = 16;

void measure(const std::string& name, const fs::path& file, int count, int runs) {
    if (!fs::exists(file)) {
        std::printf("%-10s skipped: %s not found\n", name.c_str(), file.string().c_str());
        return;
    }
    const prism::scene::Scene scene = prism::io::load_scene(file);
    const Geometry geometry(scene);
    const Rays rays = make_rays(geometry, count - count % batch);
    const std::size_t n = rays.bounce.size();
    const char* route = geometry.route() == prism::BatchRoute::leaf_lanes    ? "leaf lanes"
                        : geometry.route() == prism::BatchRoute::index_lanes ? "index lanes"
                                                                              : "ray by ray";

    std::vector<prism::Hit<Real>> alone(n), batched(n);
    std::vector<std::uint8_t> found_alone(n), found_batched(n), blocked_alone(n), blocked_batched(n);
    const Timing closest_one = time_runs(runs, n, [&] {
        for (std::size_t i = 0; i < n; ++i) {
            prism::Ray<Real> ray = rays.bounce[i];
            found_alone[i] = prism::closest_hit(geometry, ray, alone[i]);
        }
    });
    const Timing closest_batch = time_runs(runs, n, [&] {
        for (std::size_t first = 0; first < n; first += batch) {
            prism::Ray<Real> group[batch];
            std::copy_n(rays.bounce.begin() + std::ptrdiff_t(first), batch, group);
            const std::uint32_t found = geometry.intersect(prism::RayBatch<Real>::all(group, batch), batched.data() + first);
            for (int k = 0; k < batch; ++k) found_batched[first + std::size_t(k)] = (found >> k) & 1;
        }
    });
    const Timing occluded_one = time_runs(runs, n, [&] {
        for (std::size_t i = 0; i < n; ++i) blocked_alone[i] = prism::blocked(geometry, rays.shadow[i]);
    });
    const Timing occluded_batch = time_runs(runs, n, [&] {
        for (std::size_t first = 0; first < n; first += batch) {
            const std::uint32_t blocked = geometry.occluded(
                prism::RayBatch<Real>::all(const_cast<prism::Ray<Real>*>(rays.shadow.data() + first), batch));
            for (int k = 0; k < batch; ++k) blocked_batched[first + std::size_t(k)] = (blocked >> k) & 1;
        }
    });
    std::size_t hits = 0, blocked = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (found_alone[i] != found_batched[i] || (found_alone[i] && !same_hit(alone[i], batched[i])))
            throw std::runtime_error(name + ": bounce ray " + std::to_string(i) + " hit otherwise in a batch");
        if (blocked_alone[i] != blocked_batched[i])
            throw std::runtime_error(name + ": shadow ray " + std::to_string(i) + " answered otherwise in a batch");
        hits += found_alone[i];
        blocked += blocked_alone[i];
    }
    if (hits < n / 2) throw std::runtime_error(name + ": too few bounce rays hit for the figure to mean much");
    const auto row = [&](const char* query, const Timing& one, const Timing& batched_timing) {
        std::printf("%-10s %-11s %-8s one by one %7.1f ns (median %7.1f), batches of %d %7.1f ns (median %7.1f): %.3f\n",
                    name.c_str(), route, query, one.min(), one.median(), batch, batched_timing.min(),
                    batched_timing.median(), batched_timing.min() / one.min());
    };
    row("closest", closest_one, closest_batch);
    row("any hit", occluded_one, occluded_batch);
    std::printf("%-10s %zu rays: %zu bounce rays hit, %zu shadow rays blocked; every batch answer is the ray's own\n",
                name.c_str(), n, hits, blocked);
}

}  // namespace

int main(int argc, char** argv) {
    int count = 1 << 16, runs = 7;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if ((arg == "--rays" || arg == "--runs") && i + 1 < argc) (arg == "--rays" ? count : runs) = std::stoi(argv[++i]);
        else {
            std::fprintf(stderr, "usage: prism_seam_bench [--rays N] [--runs N]\n");
            return 2;
        }
    }
    if (count < batch || runs < 1) {
        std::fprintf(stderr, "prism_seam_bench: --rays must be at least %d and --runs at least 1\n", batch);
        return 2;
    }
    try {
        measure("path_diffuse", hw7 / "pathTracing/inputs/cornellbox_jaroslav_path_diffuse.xml", count, runs);
        measure("veach_ajar", hw7 / "veach-ajar/inputs/scene.xml", count, runs);
    } catch (const std::exception& error) {
        std::fprintf(stderr, "prism_seam_bench: %s\n", error.what());
        return 1;
    }
    return 0;
}
