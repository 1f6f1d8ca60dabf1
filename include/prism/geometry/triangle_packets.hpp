// A mesh's triangles packed N at a time, SoA, for the wide BVH's leaves, and the watertight
// test (geometry/watertight.hpp, Woop, Benthin, Wald 2013) run on a whole packet with one SIMD
// instruction stream (simd/pack.hpp). It computes every lane with the scalar test's operations
// in the scalar test's order, so each lane's edge functions, t and barycentrics are the scalar
// test's bits; the lanes that pass are then accepted one by one in slot order against the
// shrinking t_max, exactly as the scalar leaf loop does. The packed test is therefore as
// watertight as the scalar one and picks the same triangle on every tie.
// DoubleRefine runs the same test on packets of double vertices under float traversal.
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/geometry/double_refine.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/ray_lanes.hpp>
#include <prism/geometry/watertight.hpp>
#include <prism/memory/huge_page_allocator.hpp>
#include <prism/parallel/for_each_run.hpp>
#include <prism/simd/opaque.hpp>
#include <prism/simd/pack.hpp>
#include <prism/simd/prefetch.hpp>

#include <glm/gtc/type_ptr.hpp>

#include <array>
#include <bit>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

namespace prism {

// The intersectors with a packed test; the others (NaiveEpsilon) stay scalar in a wide BVH.
template <class I>
concept PacketIntersector = std::same_as<I, Watertight> || std::same_as<I, DoubleRefine>;

template <class Intersector, Scalar Real, int N>
class TrianglePackets {
public:
    using Storage = typename Intersector::template Storage<Real>;
    using Prepared = typename Intersector::template Prepared<Real>;
    using Pack = simd::Pack<Storage, N>;

    // What the packed test needs of a ray: the scalar test's own set-up, by reference; each
    // leaf call broadcasts it into packs once, before its packet loop (LeafRay).
    // Packs made once per ray cost six vector stores per ray and six lines the leaf then read;
    // a copy of the set-up was read back as one vector from the scalar stores that had just
    // made it, which no store forwards (70% of the copy's samples, 4% of a course profile).
    // Not copyable: a copy would outlive the ray it refers to.
    struct PackedRay {
        const Watertight::Prepared<Storage>& ray;
        explicit PackedRay(const Prepared& prepared) : ray(watertight_ray(prepared)) {}
        PackedRay(const PackedRay&) = delete;
        PackedRay& operator=(const PackedRay&) = delete;
    };

    TrianglePackets() = default;

    // Whether a packet also holds its slots' source numbers (TriangleMesh::source_triangle):
    // where its vertices leave at least that much of their last cache line unused (float: 288
    // bytes of vertices in a 320-byte packet), so the numbers cost no memory and sit on a line
    // the test has just read. A merged index looks its hit's number up after the traversal,
    // and the separate array's load missed the cache: a fifth of SceneIndex::closest_one's
    // samples on the course's diffuse rays.
    static constexpr std::size_t vertex_bytes = 9 * N * sizeof(Storage);
    static constexpr bool keeps_sources =
        vertex_bytes % simd::cache_line_bytes != 0 &&
        simd::cache_line_bytes - vertex_bytes % simd::cache_line_bytes >= N * sizeof(std::uint32_t);

    // `triangles` in slot order, a multiple of N of them (the wide BVH pads its leaves), and
    // `sources`, each slot's source number, kept where keeps_sources.
    TrianglePackets(std::span<const std::array<Vec3<Storage>, 3>> triangles, std::span<const std::uint32_t> sources) {
        packets_.resize(triangles.size() / N);
        normals_.resize(triangles.size());
        // Each packet is written from its own slots only: large meshes fill theirs in parallel
        // (a twentieth of the dragon's build on one thread).
        const auto fill = [&](std::size_t first_packet, std::size_t end_packet) {
            for (std::size_t slot = first_packet * N; slot < end_packet * N; ++slot) {
                Packet& packet = packets_[slot / N];
                const auto& p = triangles[slot];
                for (int vertex = 0; vertex < 3; ++vertex)
                    for (int axis = 0; axis < 3; ++axis) packet.vertices[vertex][axis][slot % N] = p[vertex][axis];
                if constexpr (keeps_sources) packet.sources[slot % N] = sources[slot];
                // The back-face test's normal, rounded as TriangleMesh's scalar loop rounds it.
                normals_[slot] = Vec3<Real>(glm::cross(p[1] - p[0], p[2] - p[0]));
            }
        };
        constexpr std::size_t grain = 2048;  // packets per task
        for_each_run(packets_.size(), grain, fill);
    }

    std::size_t memory_bytes() const {
        return packets_.capacity() * sizeof(Packet) + normals_.capacity() * sizeof(Vec3<Real>);
    }

    // Closest hit among slots [first, first + count) (first a multiple of N); lowers t_limit.
    // Forced inline into the traversal's leaf callback, as is `test`: GCC had kept it a function
    // of its own (26% of a dragon primary profile), called once per leaf.
    PRISM_FORCE_INLINE bool intersect(const PackedRay& ray, const Vec3<Real>& direction, std::uint32_t first, std::uint32_t count,
                   Real t_min, Real& t_limit, Hit<Real>& hit, bool cull_back_faces) const {
        bool found = false;
        const LeafRay leaf_ray(ray.ray);
        for (std::uint32_t base = first; base < first + count; base += N) {
            alignas(64) Storage t[N], b1[N], b2[N];
            std::uint32_t lanes = test(packets_[base / N], leaf_ray, Storage(t_min), Storage(t_limit), t, b1, b2);
            lanes &= lane_mask(first + count - base);
            while (lanes != 0) {
                const int lane = std::countr_zero(lanes);
                lanes &= lanes - 1;
                const std::uint32_t slot = base + std::uint32_t(lane);
                if (cull_back_faces && glm::dot(normals_[slot], direction) > 0) continue;
                // The scalar loop's acceptance, lane by lane in slot order: later ties win.
                if (!(t[lane] <= Storage(t_limit))) continue;
                t_limit = Real(t[lane]);
                hit.t = t_limit;
                hit.primitive = slot;
                hit.b1 = Real(b1[lane]);
                hit.b2 = Real(b2[lane]);
                found = true;
            }
        }
        return found;
    }

    // The transposed test: several rays, one in each lane of a pack, against one triangle at a
    // time (SceneIndex::closest_dense: the camera rays of a row, whose closest hits among a
    // small scene's few triangles had cost a camera ray more instructions than its shading).
    // Each lane computes the scalar test's operations in the scalar test's order, on its own
    // ray's permuted axes and shear, so its edge functions, t and barycentrics are the scalar
    // test's bits; the slots are taken in order against each lane's shrinking t_max, as the
    // leaf loop accepts them, so each lane ends with the hit intersect gives its ray alone.
    // Only Watertight: DoubleRefine's rays carry a double refinement of their own.
    static constexpr bool tests_ray_lanes = std::is_same_v<Intersector, Watertight>;
    static constexpr int ray_lanes = 8;
    using LanePack = simd::Pack<Storage, ray_lanes>;
    using LaneMask = simd::Mask<Storage, ray_lanes>;

    // The rays of the lanes, each lane's set-up as Watertight::Prepared makes it, transposed.
    struct RayLanes {
        LanePack origin_x, origin_y, origin_z;  // along each lane's kx, ky, kz
        LanePack sx, sy, sz;
        LanePack direction[3];  // the back-face test's direction, per world axis
        LanePack t_min;
        // Which world axis each lane's kx, ky and kz is: is 0, is 1 (else 2).
        LaneMask x_is[2], y_is[2], z_is[2];

        // From `count` (<= ray_lanes) rays; the lanes past them copy ray 0 and are left out
        // by the caller's lane bits. Watertight::Prepared's set-up, lane by lane: the same
        // comparisons choose the same axes (max_dimension's, then the swap), and the same
        // divisions give the same shear, bit for bit. Made one ray at a time through
        // Prepared, the set-up had cost as many instructions as the lanes' tests.
        RayLanes(const Ray<Real>* rays, int count) {
            // Only Watertight's packets test ray lanes, and they store Real (tests_ray_lanes).
            static_assert(std::is_same_v<Storage, Real> && ray_lanes == 8);
            LanePack fields[ray_lanes];
            rays_as_lanes(rays, count, fields);
            const LanePack zero = LanePack::broadcast(0);
            const LanePack origin[3] = {fields[0], fields[1], fields[2]};
            for (int axis = 0; axis < 3; ++axis) direction[axis] = fields[3 + axis];
            t_min = fields[6];
            LanePack magnitude[3];
            for (int axis = 0; axis < 3; ++axis)
                magnitude[axis] = select(direction[axis] < zero, -direction[axis], direction[axis]);
            // kz = max_dimension(|d|): x > y ? (x > z ? 0 : 2) : (y > z ? 1 : 2).
            const LaneMask x_over_y = magnitude[0] > magnitude[1];
            const LaneMask z_0 = x_over_y & (magnitude[0] > magnitude[2]);
            const LaneMask z_1 = (!x_over_y) & (magnitude[1] > magnitude[2]);
            const LaneMask z_2 = !(z_0 | z_1);
            // kx = kz + 1 and ky = kx + 1 (mod 3), swapped where d[kz] < 0.
            const auto pick = [](const LaneMask& is_0, const LaneMask& is_1, const LanePack* v) {
                return select(is_0, v[0], select(is_1, v[1], v[2]));
            };
            const LanePack d_z = pick(z_0, z_1, direction);
            const LaneMask swap = d_z < zero;
            const auto either = [&](const LaneMask& when_swapped, const LaneMask& otherwise) {
                return (swap & when_swapped) | ((!swap) & otherwise);
            };
            z_is[0] = z_0;
            z_is[1] = z_1;
            // Unswapped, kx is 0 where kz is 2, 1 where kz is 0; ky is 0 where kz is 1, 1 where kz is 2.
            x_is[0] = either(z_1, z_2);
            x_is[1] = either(z_2, z_0);
            y_is[0] = either(z_2, z_1);
            y_is[1] = either(z_0, z_2);
            origin_x = pick(x_is[0], x_is[1], origin);
            origin_y = pick(y_is[0], y_is[1], origin);
            origin_z = pick(z_is[0], z_is[1], origin);
            sx = pick(x_is[0], x_is[1], direction) / d_z;
            sy = pick(y_is[0], y_is[1], direction) / d_z;
            sz = LanePack::broadcast(1) / d_z;
        }
    };

    // Each lane's closest hit so far: t_max lowered by every hit, and the hit's slot and
    // barycentrics; `found`, bit per lane.
    struct LaneHits {
        LanePack t_max = LanePack::broadcast(0);
        LanePack b1 = LanePack::broadcast(0), b2 = LanePack::broadcast(0);
        std::array<std::uint32_t, ray_lanes> slot{};
        std::uint32_t found = 0;
    };

    // Closest hits among slots [first, first + count) for the lanes of `lanes`.
    PRISM_FORCE_INLINE void intersect_lanes(const RayLanes& rays, std::uint32_t first, std::uint32_t count,
                                                std::uint32_t lanes, LaneHits& hits, bool cull_back_faces) const
        requires tests_ray_lanes
    {
        for (std::uint32_t slot = first; slot < first + count; ++slot) {
            SlotLanes test;
            if (!test_slot(rays, slot, lanes, test, cull_back_faces)) continue;
            const LaneMask accepted = test.accepted & (test.t > rays.t_min) & (test.t <= hits.t_max);
            std::uint32_t taken = accepted.bits() & lanes;
            if (taken == 0) continue;
            hits.t_max = select(accepted, test.t, hits.t_max);
            hits.b1 = select(accepted, test.v * test.inverse_det, hits.b1);
            hits.b2 = select(accepted, test.w * test.inverse_det, hits.b2);
            hits.found |= taken;
            for (; taken != 0; taken &= taken - 1) hits.slot[std::size_t(std::countr_zero(taken))] = slot;
        }
    }

    // The lanes of `lanes` that meet one of slots [first, first + count) in (t_min, t_max), each
    // lane's answer the scalar `occluded`'s for its ray (open at t_max).
    PRISM_FORCE_INLINE std::uint32_t occluded_lanes(const RayLanes& rays, std::uint32_t first, std::uint32_t count,
                                                        std::uint32_t lanes, const LanePack& t_max) const
        requires tests_ray_lanes
    {
        std::uint32_t blocked = 0;
        for (std::uint32_t slot = first; slot < first + count && lanes != 0; ++slot) {
            SlotLanes test;
            if (!test_slot(rays, slot, lanes, test, false)) continue;
            const std::uint32_t hit = (test.accepted & (test.t > rays.t_min) & (test.t < t_max)).bits() & lanes;
            blocked |= hit;
            lanes &= ~hit;
        }
        return blocked;
    }

    // The source number of `slot`, as given to the constructor.
    std::uint32_t source(std::uint32_t slot) const
        requires keeps_sources
    {
        return packets_[slot / N].sources[slot % N];
    }

    // Requests the packet that holds slot `first` (a leaf's first slot) from memory.
    PRISM_PREFETCH_INLINE void prefetch(std::uint32_t first) const { simd::prefetch(packets_[first / N]); }

    // Whether any of slots [first, first + count) is hit in (t_min, t_limit).
    PRISM_FORCE_INLINE bool occluded(const PackedRay& ray, std::uint32_t first, std::uint32_t count, Real t_min, Real t_limit) const {
        const LeafRay leaf_ray(ray.ray);
        for (std::uint32_t base = first; base < first + count; base += N) {
            alignas(64) Storage t[N], b1[N], b2[N];
            std::uint32_t lanes = test(packets_[base / N], leaf_ray, Storage(t_min), Storage(t_limit), t, b1, b2);
            lanes &= lane_mask(first + count - base);
            while (lanes != 0) {
                const int lane = std::countr_zero(lanes);
                lanes &= lanes - 1;
                // Open at t_max, as TriangleMesh's scalar test, on t rounded to Real.
                if (Real(t[lane]) < t_limit) return true;
            }
        }
        return false;
    }

private:
    struct alignas(64) PacketAlone {
        Storage vertices[3][3][N];  // [vertex][axis][lane]
    };
    struct alignas(64) PacketWithSources {
        Storage vertices[3][3][N];
        std::uint32_t sources[N];  // in the last line's otherwise unused bytes
    };
    using Packet = std::conditional_t<keeps_sources, PacketWithSources, PacketAlone>;
    static_assert(sizeof(Packet) == sizeof(PacketAlone), "the source numbers must fit the packet's padding");

    // One slot against the lanes (intersect_lanes, occluded_lanes): the lanes the watertight
    // test accepts before its interval check, their t, v, w and 1 / det.
    struct SlotLanes {
        LaneMask accepted;
        LanePack t, v, w, inverse_det;
    };
    // False where no lane of `lanes` is accepted (t left uncomputed).
    PRISM_FORCE_INLINE bool test_slot(const RayLanes& rays, std::uint32_t slot, std::uint32_t lanes, SlotLanes& out,
                                          bool cull_back_faces) const {
        const LanePack zero = LanePack::broadcast(0);
        const Packet& packet = packets_[slot / N];
        const std::size_t lane_of_slot = slot % N;
        // The slot's vertex `vertex` along each lane's permuted axis `is`.
        const auto along = [&](int vertex, const LaneMask* is) {
            const LanePack x = LanePack::broadcast(packet.vertices[vertex][0][lane_of_slot]);
            const LanePack y = LanePack::broadcast(packet.vertices[vertex][1][lane_of_slot]);
            const LanePack z = LanePack::broadcast(packet.vertices[vertex][2][lane_of_slot]);
            return select(is[0], x, select(is[1], y, z));
        };
        const LanePack a_z = along(0, rays.z_is) - rays.origin_z, b_z = along(1, rays.z_is) - rays.origin_z,
                       c_z = along(2, rays.z_is) - rays.origin_z;
        const LanePack ax = (along(0, rays.x_is) - rays.origin_x) - rays.sx * a_z;
        const LanePack ay = (along(0, rays.y_is) - rays.origin_y) - rays.sy * a_z;
        const LanePack bx = (along(1, rays.x_is) - rays.origin_x) - rays.sx * b_z;
        const LanePack by = (along(1, rays.y_is) - rays.origin_y) - rays.sy * b_z;
        const LanePack cx = (along(2, rays.x_is) - rays.origin_x) - rays.sx * c_z;
        const LanePack cy = (along(2, rays.y_is) - rays.origin_y) - rays.sy * c_z;

        LanePack u = cx * by - cy * bx;
        out.v = ax * cy - ay * cx;
        out.w = bx * ay - by * ax;
        if constexpr (std::is_same_v<Storage, float>) {
            // The paper's fallback to double on an exactly zero edge function, lane by lane.
            if (std::uint32_t zeros = ((u == zero) | (out.v == zero) | (out.w == zero)).bits() & lanes)
                edge_functions_in_double(zeros, ax, ay, bx, by, cx, cy, u, out.v, out.w);
        }
        const LanePack& v = out.v;
        const LanePack& w = out.w;
        const LaneMask outside = ((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero));
        const LanePack det = u + v + w;
        out.accepted = (!outside) & (det != zero);
        if (cull_back_faces) {
            // glm::dot's order: (x + y) + z of the products.
            const Vec3<Real>& normal = normals_[slot];
            const LanePack facing = (LanePack::broadcast(normal.x) * rays.direction[0] +
                                     LanePack::broadcast(normal.y) * rays.direction[1]) +
                                    LanePack::broadcast(normal.z) * rays.direction[2];
            out.accepted = out.accepted & !(facing > zero);
        }
        if (!(out.accepted.bits() & lanes)) return false;
        const LanePack az = rays.sz * a_z, bz = rays.sz * b_z, cz = rays.sz * c_z;
        const LanePack t_scaled = u * az + v * bz + w * cz;
        out.inverse_det = LanePack::broadcast(1) / det;
        out.t = t_scaled * out.inverse_det;
        return true;
    }

    // intersect_lanes' double fallback for the lanes of `zeros`: the scalar test's own.
    [[gnu::noinline]] static void edge_functions_in_double(std::uint32_t zeros, const LanePack& ax, const LanePack& ay,
                                                           const LanePack& bx, const LanePack& by, const LanePack& cx,
                                                           const LanePack& cy, LanePack& u, LanePack& v, LanePack& w) {
        alignas(64) Storage lanes[9][ray_lanes];
        const LanePack* inputs[9] = {&ax, &ay, &bx, &by, &cx, &cy, &u, &v, &w};
        for (int k = 0; k < 9; ++k) inputs[k]->store(lanes[k]);
        for (; zeros != 0; zeros &= zeros - 1) {
            const int i = std::countr_zero(zeros);
            const double dax = lanes[0][i], day = lanes[1][i], dbx = lanes[2][i], dby = lanes[3][i], dcx = lanes[4][i],
                         dcy = lanes[5][i];
            lanes[6][i] = Storage(dcx * dby - dcy * dbx);
            lanes[7][i] = Storage(dax * dcy - day * dcx);
            lanes[8][i] = Storage(dbx * day - dby * dax);
        }
        u = LanePack::load(lanes[6]);
        v = LanePack::load(lanes[7]);
        w = LanePack::load(lanes[8]);
    }

    static const Watertight::Prepared<Storage>& watertight_ray(const Prepared& prepared) {
        if constexpr (std::is_same_v<Intersector, DoubleRefine>)
            return prepared.ray;
        else
            return prepared;
    }

    static std::uint32_t lane_mask(std::uint32_t remaining) {
        return remaining >= std::uint32_t(N) ? (std::uint32_t(1) << N) - 1 : (std::uint32_t(1) << remaining) - 1;
    }

    // The ray's set-up as a leaf's packet loop reads it, made once per leaf before the loop:
    // the origin's components and the shear broadcast, and each permuted axis's row as one byte
    // offset into a packet, its three vertices' rows at constant displacements from it. Indexed
    // by the ray's axes inside the loop, GCC had kept nine row offsets (vertex x axis) and three
    // origin addresses live across it and spilled them to vector registers (a tenth of the
    // leaf's samples); read inside the loop, the origin was also read again after every hit's
    // stores, which may alias it.
    struct LeafRay {
        Pack origin_x, origin_y, origin_z;  // along kx, ky, kz
        Pack sx, sy, sz;
        std::size_t row_x, row_y, row_z;  // bytes from a packet's start to vertex 0's row along kx, ky, kz
        PRISM_FORCE_INLINE explicit LeafRay(const Watertight::Prepared<Storage>& ray)
            : origin_x(Pack::broadcast(glm::value_ptr(ray.origin)[ray.kx])),
              origin_y(Pack::broadcast(glm::value_ptr(ray.origin)[ray.ky])),
              origin_z(Pack::broadcast(glm::value_ptr(ray.origin)[ray.kz])),
              sx(Pack::broadcast(ray.sx)), sy(Pack::broadcast(ray.sy)), sz(Pack::broadcast(ray.sz)),
              row_x(row_offset(ray.kx)), row_y(row_offset(ray.ky)), row_z(row_offset(ray.kz)) {}
        // Indexed as an array: glm's operator[] is a switch, which GCC kept as branches.
        static std::size_t row_offset(int axis) { return std::size_t(axis) * N * sizeof(Storage); }
    };

    // Watertight::intersect on every lane: the lanes hit in (t_min, t_max], with their t and
    // barycentrics stored. Same operations, same order, so the same bits as the scalar test.
    PRISM_FORCE_INLINE static std::uint32_t test(const Packet& packet, const LeafRay& ray, Storage t_min, Storage t_max,
                              Storage* t_out, Storage* b1_out, Storage* b2_out) {
        static_assert(std::is_standard_layout_v<Packet> && offsetof(Packet, vertices) == 0);
        const auto* packet_bytes = reinterpret_cast<const unsigned char*>(&packet);
        constexpr std::size_t vertex_stride = 3 * N * sizeof(Storage);
        // Opaque in the loop: see simd/opaque.hpp.
        const std::size_t row_x = simd::opaque(ray.row_x), row_y = simd::opaque(ray.row_y), row_z = simd::opaque(ray.row_z);
        const auto row = [&](std::size_t axis_row, int vertex) {
            return Pack::load(reinterpret_cast<const Storage*>(packet_bytes + axis_row + std::size_t(vertex) * vertex_stride));
        };
        const Pack sx = ray.sx, sy = ray.sy, sz = ray.sz;
        const Pack a_z = row(row_z, 0) - ray.origin_z, b_z = row(row_z, 1) - ray.origin_z, c_z = row(row_z, 2) - ray.origin_z;
        const Pack ax = (row(row_x, 0) - ray.origin_x) - sx * a_z;
        const Pack ay = (row(row_y, 0) - ray.origin_y) - sy * a_z;
        const Pack bx = (row(row_x, 1) - ray.origin_x) - sx * b_z;
        const Pack by = (row(row_y, 1) - ray.origin_y) - sy * b_z;
        const Pack cx = (row(row_x, 2) - ray.origin_x) - sx * c_z;
        const Pack cy = (row(row_y, 2) - ray.origin_y) - sy * c_z;

        Pack u = cx * by - cy * bx;
        Pack v = ax * cy - ay * cx;
        Pack w = bx * ay - by * ax;
        const Pack zero = Pack::broadcast(0);
        if constexpr (std::is_same_v<Storage, float>) {
            // The paper's fallback to double on an exactly zero edge function, lane by lane.
            if (std::uint32_t zeros = ((u == zero) | (v == zero) | (w == zero)).bits()) {
                alignas(64) float lanes[8][N];
                const Pack* inputs[6] = {&ax, &ay, &bx, &by, &cx, &cy};
                for (int k = 0; k < 6; ++k) inputs[k]->store(lanes[k]);
                u.store(lanes[6]);
                v.store(lanes[7]);
                alignas(64) float w_lanes[N];
                w.store(w_lanes);
                while (zeros != 0) {
                    const int i = std::countr_zero(zeros);
                    zeros &= zeros - 1;
                    const double dax = lanes[0][i], day = lanes[1][i], dbx = lanes[2][i], dby = lanes[3][i],
                                 dcx = lanes[4][i], dcy = lanes[5][i];
                    lanes[6][i] = float(dcx * dby - dcy * dbx);
                    lanes[7][i] = float(dax * dcy - day * dcx);
                    w_lanes[i] = float(dbx * day - dby * dax);
                }
                u = Pack::load(lanes[6]);
                v = Pack::load(lanes[7]);
                w = Pack::load(w_lanes);
            }
        }
        const auto outside = ((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero));
        const Pack det = u + v + w;
        auto accepted = (!outside) & (det != zero);
        if (!accepted.any()) return 0;

        const Pack az = sz * a_z, bz = sz * b_z, cz = sz * c_z;
        const Pack t_scaled = u * az + v * bz + w * cz;
        const Pack inverse_det = Pack::broadcast(1) / det;
        const Pack t = t_scaled * inverse_det;
        accepted = accepted & (t > Pack::broadcast(t_min)) & (t <= Pack::broadcast(t_max));
        const std::uint32_t lanes = accepted.bits();
        if (lanes == 0) return 0;
        t.store(t_out);
        (v * inverse_det).store(b1_out);
        (w * inverse_det).store(b2_out);
        return lanes;
    }

    // In transparent huge pages where they fill one (memory/huge_page_allocator.hpp; the
    // constructor writes every slot), as the nodes are (WideBvhTree::nodes_).
    HugePageVector<Packet> packets_;
    std::vector<Vec3<Real>> normals_;  // per slot, read only when culling back faces
};

// The packets a policy's meshes keep: none for the binary BVH, brute force or a scalar-only
// intersector; TrianglePackets for a wide BVH (a policy with a packet_width) of a packed test.
struct NoTrianglePackets {
    struct PackedRay {
        template <class Prepared>
        explicit PackedRay(const Prepared&) {}
    };
};

template <class Policy, class Real, bool = requires { Policy::packet_width; } &&
                                          PacketIntersector<typename Policy::Intersector>>
struct TrianglePacketsOf {
    using type = NoTrianglePackets;
};
template <class Policy, class Real>
struct TrianglePacketsOf<Policy, Real, true> {
    using type = TrianglePackets<typename Policy::Intersector, Real, Policy::packet_width>;
};

}  // namespace prism
