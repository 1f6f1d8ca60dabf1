// TrianglePackets against the scalar leaf loop (TriangleMesh's, without a wide BVH): leaves of
// every count 1..2N, one or two packets, laid out as WideBvhTree lays them out (each padded to a
// multiple of N with repeats of its last triangle; accel/wide_bvh_tree.hpp). Every hit must be
// the scalar loop's to the bit (t, barycentrics, slot: the same tie order), every occlusion
// answer the same, and every slot's source number kept.
#include <prism/geometry/double_refine.hpp>
#include <prism/geometry/triangle_packets.hpp>
#include <prism/geometry/watertight.hpp>

#include <doctest/doctest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <type_traits>
#include <vector>

namespace {

template <class T>
auto bits(T value) {
    if constexpr (std::is_same_v<T, float>)
        return std::bit_cast<std::uint32_t>(value);
    else
        return std::bit_cast<std::uint64_t>(value);
}

template <class Intersector, class Real, int N>
void check_every_leaf_count() {
    using Packets = prism::TrianglePackets<Intersector, Real, N>;
    using Storage = typename Packets::Storage;
    using Triangle = std::array<prism::Vec3<Storage>, 3>;
    std::mt19937 random(N * 100 + (std::is_same_v<Real, float> ? 1 : 2) + (std::is_same_v<Intersector, prism::Watertight> ? 10 : 20));
    std::uniform_real_distribution<double> unit(-1, 1);
    // Small triangles around the z axis at depths 2..3; every fifth a copy of the one before (an
    // exact tie, which the later slot wins) and every seventh sharing the previous one's edge
    // (rays through the edge).
    std::vector<Triangle> triangles;
    std::vector<std::uint32_t> sources;
    const auto random_triangle = [&](std::size_t index) {
        if (index > 0 && index % 5 == 0) return triangles.back();
        const prism::Vec3<Storage> centre(Storage(0.4 * unit(random)), Storage(0.4 * unit(random)), Storage(-2.5 + 0.5 * unit(random)));
        Triangle t;
        for (auto& p : t) p = centre + prism::Vec3<Storage>(Storage(0.5 * unit(random)), Storage(0.5 * unit(random)), Storage(0.1 * unit(random)));
        if (index > 0 && index % 7 == 0) {
            t[0] = triangles.back()[1];
            t[1] = triangles.back()[0];
        }
        return t;
    };
    struct Leaf {
        std::uint32_t first, count;
    };
    std::vector<Leaf> leaves;
    const auto add_leaf = [&](std::uint32_t count) {
        const auto first = std::uint32_t(triangles.size());
        for (std::uint32_t i = 0; i < count; ++i) {
            triangles.push_back(random_triangle(i));
            sources.push_back(std::uint32_t(random()));
        }
        while (triangles.size() % N != 0) {
            triangles.push_back(triangles.back());
            sources.push_back(sources.back());
        }
        leaves.push_back({first, count});
    };
    // Every count twice, so that packets follow packets.
    for (int round = 0; round < 2; ++round)
        for (std::uint32_t count = 1; count <= 2 * N; ++count) add_leaf(count);
    const Packets packets(triangles, sources);

    if constexpr (Packets::keeps_sources) {
        std::size_t wrong_sources = 0;
        for (std::uint32_t slot = 0; slot < triangles.size(); ++slot) wrong_sources += packets.source(slot) != sources[slot];
        CHECK(wrong_sources == 0);
    }
    // Float packets keep the source numbers, double ones where N = 4 only (288 bytes of 320).
    CHECK(Packets::keeps_sources == (std::is_same_v<Storage, float> || N == 4));

    std::size_t hits = 0, hits_at_t_max = 0, later_ties = 0, closest_differ = 0, occluded_differ = 0, occluded = 0;
    std::vector<std::size_t> hits_per_count(2 * N + 1, 0);
    for (int r = 0; r < 3000; ++r) {
        const prism::Vec3<Real> origin(Real(0.3 * unit(random)), Real(0.3 * unit(random)), Real(0.5 * unit(random)));
        const prism::Vec3<Real> target(Real(0.6 * unit(random)), Real(0.6 * unit(random)), Real(-2.5));
        // Every third ray ends among the triangles, so t_max rejects some hits; every third
        // ends exactly at its closest hit in the leaf, which must stay a hit (the interval is
        // closed there, and the division is skipped only for lanes certainly beyond it); every
        // fourth points away, every triangle behind its origin.
        const Real t_max = r % 3 == 0 ? Real(2.5 + 0.4 * unit(random)) : prism::infinity<Real>;
        const prism::Vec3<Real> direction = glm::normalize(target - origin) * Real(r % 4 == 1 ? -1 : 1);
        const prism::Ray<Real> whole{origin, direction, Real(0), t_max};
        const typename Intersector::template Prepared<Real> prepared(whole);
        const typename Packets::PackedRay packed(prepared);
        for (const Leaf& leaf : leaves) {
            prism::Ray<Real> ray = whole;
            if (r % 3 == 2) {
                for (std::uint32_t slot = leaf.first; slot < leaf.first + leaf.count; ++slot) {
                    const Triangle& p = triangles[slot];
                    prism::TriangleHit<Real> h;
                    if (Intersector::intersect(prepared, p[0], p[1], p[2], ray.t_min, ray.t_max, h)) ray.t_max = h.t;
                }
            }
            for (const bool cull : {false, true}) {
                Real t_scalar = ray.t_max, t_packed = ray.t_max;
                prism::Hit<Real> scalar{}, packed_hit{};
                bool found_scalar = false;
                std::size_t equal_t = 0;
                for (std::uint32_t slot = leaf.first; slot < leaf.first + leaf.count; ++slot) {
                    const Triangle& p = triangles[slot];
                    if (cull && glm::dot(prism::Vec3<Real>(glm::cross(p[1] - p[0], p[2] - p[0])), ray.direction) > 0) continue;
                    prism::TriangleHit<Real> h;
                    if (Intersector::intersect(prepared, p[0], p[1], p[2], ray.t_min, t_scalar, h)) {
                        equal_t += found_scalar && h.t == t_scalar;
                        t_scalar = h.t;
                        scalar.t = h.t;
                        scalar.primitive = slot;
                        scalar.b1 = h.b1;
                        scalar.b2 = h.b2;
                        found_scalar = true;
                    }
                }
                const bool found_packed = packets.intersect(packed, ray.direction, leaf.first, leaf.count, ray.t_min, t_packed, packed_hit, cull);
                later_ties += equal_t;
                hits_at_t_max += found_scalar && t_scalar == ray.t_max && std::isfinite(ray.t_max);
                hits += found_scalar;
                if (found_scalar) ++hits_per_count[leaf.count];
                closest_differ += found_scalar != found_packed || bits(t_scalar) != bits(t_packed) ||
                                  (found_scalar && (scalar.primitive != packed_hit.primitive || bits(scalar.b1) != bits(packed_hit.b1) ||
                                                    bits(scalar.b2) != bits(packed_hit.b2)));
            }
            bool blocked = false;
            for (std::uint32_t slot = leaf.first; slot < leaf.first + leaf.count && !blocked; ++slot) {
                const Triangle& p = triangles[slot];
                prism::TriangleHit<Real> h;
                blocked = Intersector::intersect(prepared, p[0], p[1], p[2], ray.t_min, ray.t_max, h) && h.t < ray.t_max;
            }
            occluded += blocked;
            occluded_differ += blocked != packets.occluded(packed, leaf.first, leaf.count, ray.t_min, ray.t_max);
        }
    }
    MESSAGE("N " << N << ": " << hits << " hits, " << later_ties << " ties won by the later slot, " << occluded << " occluded, "
                  << hits_at_t_max << " hits at t_max");
    // The rays must exercise what the test claims: hits in leaves of every count, ties, misses.
    for (int count = 1; count <= 2 * N; ++count) CHECK(hits_per_count[std::size_t(count)] > 10);
    CHECK(later_ties > 0);
    CHECK(hits_at_t_max > 100);
    CHECK(hits < 3000 * 2 * leaves.size());
    CHECK(occluded > 0);
    CHECK(closest_differ == 0);
    CHECK(occluded_differ == 0);
}

}  // namespace

TEST_CASE_TEMPLATE("TrianglePackets: leaves of every count 1..2N hit as the scalar loop does, to the bit",
                   Real, float, double) {
    check_every_leaf_count<prism::Watertight, Real, 4>();
    check_every_leaf_count<prism::Watertight, Real, 8>();
    check_every_leaf_count<prism::DoubleRefine, Real, 4>();
    check_every_leaf_count<prism::DoubleRefine, Real, 8>();
}
