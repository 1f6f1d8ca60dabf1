// The float filter of double triangle packets (geometry/triangle_packets.hpp: DoubleRefine's,
// and Watertight's in a double tree) skips a packet's double test where it proves every lane a
// miss. Its bound is only as good as its proof: these tests aim millions
// of rays at the edges and shared vertices of fans of tiny triangles, near and far from the
// origin, and require that no lane the double test accepts was rejected by the filter, while the
// filter still rejects the lanes a ray passes well away from.
#include <prism/geometry/double_refine.hpp>
#include <prism/geometry/triangle_packets.hpp>

#include <doctest/doctest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <type_traits>
#include <vector>

namespace {

struct FilterCounts {
    std::uint64_t accepted = 0;       // lanes the double test accepts
    std::uint64_t lost = 0;           // of those, lanes the filter rejected: must stay 0
    std::uint64_t rejected = 0;       // lanes the filter rejected
    std::uint64_t rays = 0;
    std::uint64_t near_rays = 0;      // rays from within 16 radii of the fan
    std::uint64_t near_rejected = 0;  // lanes the filter rejected on those
};

// A fan of N triangles around `centre` in a random plane, radius `radius`: neighbours share a
// spoke, and all share the centre, so rays through a spoke or the centre sit on several lanes'
// edges at once.
template <int N>
std::vector<std::array<prism::Vec3<double>, 3>> fan(std::mt19937_64& random, const prism::Vec3<double>& centre, double radius) {
    std::normal_distribution<double> normal;
    prism::Vec3<double> a(normal(random), normal(random), normal(random));
    prism::Vec3<double> b(normal(random), normal(random), normal(random));
    a = glm::normalize(a);
    b = glm::normalize(b - a * glm::dot(a, b));
    std::vector<std::array<prism::Vec3<double>, 3>> triangles;
    const double step = 2 * 3.14159265358979323846 / N;
    for (int k = 0; k < N; ++k) {
        const prism::Vec3<double> p1 = centre + radius * (std::cos(k * step) * a + std::sin(k * step) * b);
        const prism::Vec3<double> p2 = centre + radius * (std::cos((k + 1) * step) * a + std::sin((k + 1) * step) * b);
        triangles.push_back({centre, p1, p2});
    }
    return triangles;
}

template <class Intersector, class Real, int N>
FilterCounts run_filter_check(std::uint64_t seed, int fans, int rays_per_fan, double centre_scale, double relative_radius) {
    using Packets = prism::TrianglePackets<Intersector, Real, N>;
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> unit(-1, 1), fraction(0, 1);
    std::uniform_int_distribution<int> pick(0, 7);
    FilterCounts counts;
    for (int f = 0; f < fans; ++f) {
        const prism::Vec3<double> centre(unit(random) * centre_scale, unit(random) * centre_scale, unit(random) * centre_scale);
        const double radius = relative_radius * std::max(1.0, centre_scale) * (0.5 + fraction(random));
        const auto triangles = fan<N>(random, centre, radius);
        const Packets packets(triangles);
        for (int r = 0; r < rays_per_fan; ++r) {
            // A target on a spoke (shared by two lanes), the centre, or a rim edge, nudged off it
            // by a random power of two of the radius (or not at all).
            const int k = int(random() % N);
            const auto& t = triangles[std::size_t(k)];
            prism::Vec3<double> target;
            switch (pick(random) % 4) {
                case 0: target = t[0]; break;
                case 1: target = t[0] + fraction(random) * (t[1] - t[0]); break;
                case 2: target = t[1] + fraction(random) * (t[2] - t[1]); break;
                default: target = t[0] + fraction(random) * (t[1] - t[0]) + fraction(random) * 0.5 * (t[2] - t[1]); break;
            }
            if (random() % 2) {
                const double nudge = radius * std::ldexp(1.0, -int(random() % 60));
                target += nudge * prism::Vec3<double>(unit(random), unit(random), unit(random));
            }
            // Origins near (a few radii) and far (up to the scene's scale) from the fan; every
            // eighth ray's direction has zero components.
            const int octaves = int(random() % 40);
            const double distance = radius * std::ldexp(1.0, octaves);
            prism::Vec3<double> origin =
                target + distance * prism::Vec3<double>(unit(random), unit(random), unit(random));
            if (pick(random) == 0) {
                const int keep = int(random() % 3);
                for (int axis = 0; axis < 3; ++axis)
                    if (axis != keep) origin[axis] = target[axis];
            }
            const prism::Ray<Real> ray{prism::Vec3<Real>(origin), prism::Vec3<Real>(target - origin), Real(0),
                                       prism::infinity<Real>};
            const typename Packets::Prepared prepared(ray);
            const typename Packets::PackedRay packed(prepared);
            const std::uint32_t kept = packets.filter_lanes(packed, 0);
            const std::uint32_t hit = packets.test_lanes(packed, 0, -prism::infinity<double>, prism::infinity<double>);
            counts.accepted += std::uint64_t(std::popcount(hit));
            counts.lost += std::uint64_t(std::popcount(hit & ~kept));
            counts.rejected += std::uint64_t(N - std::popcount(kept));
            ++counts.rays;
            if (octaves <= 4) {
                ++counts.near_rays;
                counts.near_rejected += std::uint64_t(N - std::popcount(kept));
            }
        }
    }
    return counts;
}

template <class Intersector, class Real, int N>
void check_filter() {
    // Ordinary fans near the origin, tiny fans (the dragon's scale), and tiny fans far away,
    // where float rounding of the vertices is larger than the triangles themselves.
    struct Case {
        double centre_scale, relative_radius;
    };
    const Case cases[] = {{1, 0.1}, {10, 1e-4}, {1e3, 1e-6}, {1e5, 1e-9}, {1e-3, 1e-3}, {1e7, 1e-3}};
    std::uint64_t seed = 11;
    for (const Case& c : cases) {
        CAPTURE(c.centre_scale);
        CAPTURE(c.relative_radius);
        const auto counts = run_filter_check<Intersector, Real, N>(seed++, 2000, 256, c.centre_scale, c.relative_radius);
        CHECK(counts.lost == 0);
        // Rays aimed at the fan hit it, so the check is not vacuous; except a float ray far out,
        // whose own rounding (an ulp of 10^5 is 0.008) is larger than the fan (10^-4).
        if (std::is_same_v<Real, double> || c.centre_scale * c.relative_radius > 1e-4)
            CHECK(counts.accepted > counts.rays / 2);
        else
            CHECK(counts.accepted > 0);
        // And the filter rejects lanes where the fan is large against float's rounding of the
        // coordinates and the origin is near it (measured: 4.3-5.3 of 8 lanes, 1.7-2.2 of 4).
        if (c.relative_radius >= 1e-4) CHECK(counts.near_rejected * 2 > counts.near_rays * (N - 2));
    }
}

}  // namespace

TEST_CASE_TEMPLATE("DoubleRefine's float filter never rejects a lane the double test accepts (N = 8)", Real, float, double) {
    check_filter<prism::DoubleRefine, Real, 8>();
}

TEST_CASE_TEMPLATE("DoubleRefine's float filter never rejects a lane the double test accepts (N = 4)", Real, float, double) {
    check_filter<prism::DoubleRefine, Real, 4>();
}

// A double tree's Watertight packets are filtered the same way; their rays are double, so the
// filter also rounds the origin (float Watertight packets have no filter).
TEST_CASE("Watertight double packets: the float filter never rejects a lane the double test accepts") {
    static_assert(!prism::TrianglePackets<prism::Watertight, float, 8>::filtered);
    check_filter<prism::Watertight, double, 8>();
    check_filter<prism::Watertight, double, 4>();
}

// Rays that miss a packet by far: the filter rejects every lane, so the double packet is not
// read at all.
TEST_CASE_TEMPLATE("DoubleRefine's float filter rejects every lane of a packet the ray passes far from", Real, float, double) {
    std::mt19937_64 random(5);
    const auto triangles = fan<8>(random, prism::Vec3<double>(3, -2, 5), 0.5);
    const prism::TrianglePackets<prism::DoubleRefine, Real, 8> packets(triangles);
    const prism::Ray<Real> ray{prism::Vec3<Real>(0), prism::Vec3<Real>(Real(-1), Real(0.25), Real(0.5)), Real(0),
                               prism::infinity<Real>};
    const prism::DoubleRefine::Prepared<Real> prepared(ray);
    const typename prism::TrianglePackets<prism::DoubleRefine, Real, 8>::PackedRay packed(prepared);
    CHECK(packets.filter_lanes(packed, 0) == 0);
    CHECK(packets.test_lanes(packed, 0, -prism::infinity<double>, prism::infinity<double>) == 0);
}
