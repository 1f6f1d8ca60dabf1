// A mesh's triangles packed N at a time, SoA, for the wide BVH's leaves, and the watertight
// test (geometry/watertight.hpp, Woop, Benthin, Wald 2013) run on a whole packet with one SIMD
// instruction stream (simd/pack.hpp). It computes every lane with the scalar test's operations
// in the scalar test's order, so each lane's edge functions, t and barycentrics are the scalar
// test's bits; the lanes that pass are then accepted one by one in slot order against the
// shrinking t_max, exactly as the scalar leaf loop does. The packed test is therefore as
// watertight as the scalar one and picks the same triangle on every tie.
// DoubleRefine runs the same test on packets of double vertices under float traversal.
#pragma once

#include <prism/geometry/double_refine.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/watertight.hpp>
#include <prism/parallel/for_each_run.hpp>
#include <prism/simd/pack.hpp>
#include <prism/simd/prefetch.hpp>

#include <array>
#include <bit>
#include <concepts>
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
    // A leaf of at most `half` triangles is one half-width packet, tested with half-width
    // instructions (float: an xmm register where N = 8; double: a ymm one): about a third of a
    // course mesh's lanes had been padding in full packets, and a double leaf test is bound by
    // its arithmetic (bench/RESULTS.md, "double2"), which a 4-lane division halves.
    static constexpr int half = N / 2;
    template <int W> using PackOf = simd::Pack<Storage, W>;

    // What the packed test needs of a ray, broadcast once per ray: for both widths, each its
    // own broadcasts (a ray takes both kinds of leaves).
    template <int W>
    struct RayLanes {
        PackOf<W> origin[3];
        PackOf<W> sx, sy, sz;
        explicit RayLanes(const Watertight::Prepared<Storage>& ray) {
            for (int axis = 0; axis < 3; ++axis) origin[axis] = PackOf<W>::broadcast(ray.origin[axis]);
            sx = PackOf<W>::broadcast(ray.sx);
            sy = PackOf<W>::broadcast(ray.sy);
            sz = PackOf<W>::broadcast(ray.sz);
        }
    };
    struct PackedRay {
        int kx, ky, kz;
        RayLanes<N> full;
        RayLanes<half> halved;
        explicit PackedRay(const Prepared& prepared)
            : kx(watertight_ray(prepared).kx), ky(watertight_ray(prepared).ky), kz(watertight_ray(prepared).kz),
              full(watertight_ray(prepared)), halved(watertight_ray(prepared)) {}
    };

    TrianglePackets() = default;

    // A packet of W lanes: the vertices SoA, and where keeps_sources, the slots' source numbers
    // (TriangleMesh::source_triangle) in bytes the vertices leave unused: float: 288 bytes of
    // vertices in a 320-byte full packet, 144 in a 160-byte half one; so the numbers cost no
    // memory and sit on a line the test has just read. A merged index looks its hit's number up
    // after the traversal, and the separate array's load missed the cache: a fifth of
    // SceneGeometry::intersect's samples on the course's diffuse rays. Half packets are aligned
    // to 32 bytes, not a cache line: rows of at most 32 bytes at 32-byte steps never straddle a
    // line, and a 160- or 288-byte packet spans as many lines either way, so the 32 bytes a
    // line's alignment would add are saved.
    template <int W>
    static constexpr std::size_t alignment = W == N ? simd::cache_line_bytes : 32;
    template <int W>
    static constexpr std::size_t vertex_bytes = 9 * W * sizeof(Storage);
    template <int W>
    static constexpr bool sources_fit = vertex_bytes<W> % alignment<W> != 0 &&
                                        alignment<W> - vertex_bytes<W> % alignment<W> >= W * sizeof(std::uint32_t);
    // Both kinds hold them or neither does, so that source() needs no other array.
    static constexpr bool keeps_sources = sources_fit<N> && sources_fit<half>;

    // `triangles` in slot order (the wide BVH's: leaves padded to N slots below `half_begin`,
    // to N/2 from it on; accel/wide_bvh_tree.hpp), and `sources`, each slot's source number,
    // kept where keeps_sources.
    TrianglePackets(std::span<const std::array<Vec3<Storage>, 3>> triangles, std::span<const std::uint32_t> sources,
                    std::uint32_t half_begin)
        : half_begin_(half_begin) {
        packets_.resize(half_begin / N);
        halves_.resize((triangles.size() - half_begin) / half);
        normals_.resize(triangles.size());
        // Each packet is written from its own slots only: large meshes fill theirs in parallel
        // (a twentieth of the dragon's build on one thread).
        const auto fill = [&]<int W>(auto& packets, std::size_t first_slot, std::size_t first_packet,
                                     std::size_t end_packet) {
            for (std::size_t k = first_packet; k < end_packet; ++k) {
                auto& packet = packets[k];
                for (int lane = 0; lane < W; ++lane) {
                    const std::size_t slot = first_slot + k * W + std::size_t(lane);
                    const auto& p = triangles[slot];
                    for (int vertex = 0; vertex < 3; ++vertex)
                        for (int axis = 0; axis < 3; ++axis) packet.vertices[vertex][axis][lane] = p[vertex][axis];
                    if constexpr (keeps_sources) packet.sources[lane] = sources[slot];
                    // The back-face test's normal, rounded as TriangleMesh's scalar loop rounds it.
                    normals_[slot] = Vec3<Real>(glm::cross(p[1] - p[0], p[2] - p[0]));
                }
            }
        };
        constexpr std::size_t grain = 2048;  // packets per task
        for_each_run(packets_.size(), grain,
                     [&](std::size_t first, std::size_t end) { fill.template operator()<N>(packets_, 0, first, end); });
        for_each_run(halves_.size(), grain, [&](std::size_t first, std::size_t end) {
            fill.template operator()<half>(halves_, half_begin, first, end);
        });
    }

    std::size_t memory_bytes() const {
        return packets_.capacity() * sizeof(Packet<N>) + halves_.capacity() * sizeof(Packet<half>) +
               normals_.capacity() * sizeof(Vec3<Real>);
    }

    // Closest hit among slots [first, first + count) (a leaf of the wide BVH); lowers t_limit.
    // Forced inline into the traversal's leaf callback, as is `test`: GCC had kept it a function
    // of its own (26% of a dragon primary profile), called once per leaf.
    template <bool CullBackfaces>
    [[gnu::always_inline]] bool intersect(const PackedRay& ray, const Vec3<Real>& direction, std::uint32_t first, std::uint32_t count,
                   Real t_min, Real& t_limit, Hit<Real>& hit) const {
        if (count <= std::uint32_t(half))
            return accept<half, CullBackfaces>(half_packet(first), ray, ray.halved, direction, first, count, t_min, t_limit, hit);
        bool found = false;
        for (std::uint32_t base = first; base < first + count; base += N)
            found |= accept<N, CullBackfaces>(packets_[base / N], ray, ray.full, direction, base, first + count - base, t_min,
                                             t_limit, hit);
        return found;
    }

    // The source number of `slot`, as given to the constructor.
    std::uint32_t source(std::uint32_t slot) const
        requires keeps_sources
    {
        if (slot < half_begin_) return packets_[slot / N].sources[slot % N];
        return halves_[(slot - half_begin_) / half].sources[(slot - half_begin_) % half];
    }

    // Requests the packet that holds slot `first` (a leaf's first slot) from memory.
    void prefetch(std::uint32_t first) const {
        if (first < half_begin_)
            simd::prefetch(packets_[first / N]);
        else
            simd::prefetch(half_packet(first));
    }

    // Whether any of slots [first, first + count) is hit in (t_min, t_limit).
    [[gnu::always_inline]] bool occluded(const PackedRay& ray, std::uint32_t first, std::uint32_t count, Real t_min, Real t_limit) const {
        if (count <= std::uint32_t(half)) return blocks<half>(half_packet(first), ray, ray.halved, count, t_min, t_limit);
        for (std::uint32_t base = first; base < first + count; base += N)
            if (blocks<N>(packets_[base / N], ray, ray.full, first + count - base, t_min, t_limit)) return true;
        return false;
    }

private:
    template <int W>
    struct alignas(alignment<W>) PacketAlone {
        Storage vertices[3][3][W];  // [vertex][axis][lane]
    };
    template <int W>
    struct alignas(alignment<W>) PacketWithSources {
        Storage vertices[3][3][W];
        std::uint32_t sources[W];  // in the last line's otherwise unused bytes
    };
    template <int W>
    using Packet = std::conditional_t<keeps_sources, PacketWithSources<W>, PacketAlone<W>>;
    static_assert(sizeof(Packet<N>) == sizeof(PacketAlone<N>) && sizeof(Packet<half>) == sizeof(PacketAlone<half>),
                  "the source numbers must fit the packets' padding");

    const Packet<half>& half_packet(std::uint32_t first) const { return halves_[(first - half_begin_) / half]; }

    static const Watertight::Prepared<Storage>& watertight_ray(const Prepared& prepared) {
        if constexpr (std::is_same_v<Intersector, DoubleRefine>)
            return prepared.ray;
        else
            return prepared;
    }

    template <int W>
    static std::uint32_t lane_mask(std::uint32_t remaining) {
        return remaining >= std::uint32_t(W) ? (std::uint32_t(1) << W) - 1 : (std::uint32_t(1) << remaining) - 1;
    }

    // One packet of slots [base, base + W), of which `remaining` (or all W) are the leaf's.
    template <int W, bool CullBackfaces>
    [[gnu::always_inline]] bool accept(const Packet<W>& packet, const PackedRay& ray, const RayLanes<W>& lanes_of_ray,
                                       const Vec3<Real>& direction, std::uint32_t base, std::uint32_t remaining, Real t_min,
                                       Real& t_limit, Hit<Real>& hit) const {
        alignas(64) Storage t[W], b1[W], b2[W];
        std::uint32_t lanes = test<W>(packet, ray, lanes_of_ray, Storage(t_min), Storage(t_limit), t, b1, b2);
        lanes &= lane_mask<W>(remaining);
        bool found = false;
        while (lanes != 0) {
            const int lane = std::countr_zero(lanes);
            lanes &= lanes - 1;
            const std::uint32_t slot = base + std::uint32_t(lane);
            if constexpr (CullBackfaces) {
                if (glm::dot(normals_[slot], direction) > 0) continue;
            }
            // The scalar loop's acceptance, lane by lane in slot order: later ties win.
            if (!(t[lane] <= Storage(t_limit))) continue;
            t_limit = Real(t[lane]);
            hit.t = t_limit;
            hit.primitive = slot;
            hit.b1 = Real(b1[lane]);
            hit.b2 = Real(b2[lane]);
            found = true;
        }
        return found;
    }

    template <int W>
    [[gnu::always_inline]] static bool blocks(const Packet<W>& packet, const PackedRay& ray, const RayLanes<W>& lanes_of_ray,
                                              std::uint32_t remaining, Real t_min, Real t_limit) {
        alignas(64) Storage t[W], b1[W], b2[W];
        std::uint32_t lanes = test<W>(packet, ray, lanes_of_ray, Storage(t_min), Storage(t_limit), t, b1, b2);
        lanes &= lane_mask<W>(remaining);
        while (lanes != 0) {
            const int lane = std::countr_zero(lanes);
            lanes &= lanes - 1;
            // Open at t_max, as TriangleMesh's scalar test, on t rounded to Real.
            if (Real(t[lane]) < t_limit) return true;
        }
        return false;
    }

    // Watertight::intersect on every lane: the lanes hit in (t_min, t_max], with their t and
    // barycentrics stored. Same operations, same order, so the same bits as the scalar test.
    template <int W>
    [[gnu::always_inline]] static std::uint32_t test(const Packet<W>& packet, const PackedRay& axes, const RayLanes<W>& ray,
                                                     Storage t_min, Storage t_max, Storage* t_out, Storage* b1_out,
                                                     Storage* b2_out) {
        using Pack = PackOf<W>;
        const auto relative = [&](int vertex, int axis) {
            return Pack::load(packet.vertices[vertex][axis]) - ray.origin[axis];
        };
        const Pack a_z = relative(0, axes.kz), b_z = relative(1, axes.kz), c_z = relative(2, axes.kz);
        const Pack ax = relative(0, axes.kx) - ray.sx * a_z;
        const Pack ay = relative(0, axes.ky) - ray.sy * a_z;
        const Pack bx = relative(1, axes.kx) - ray.sx * b_z;
        const Pack by = relative(1, axes.ky) - ray.sy * b_z;
        const Pack cx = relative(2, axes.kx) - ray.sx * c_z;
        const Pack cy = relative(2, axes.ky) - ray.sy * c_z;

        Pack u = cx * by - cy * bx;
        Pack v = ax * cy - ay * cx;
        Pack w = bx * ay - by * ax;
        const Pack zero = Pack::broadcast(0);
        if constexpr (std::is_same_v<Storage, float>) {
            // The paper's fallback to double on an exactly zero edge function, lane by lane.
            if (std::uint32_t zeros = ((u == zero) | (v == zero) | (w == zero)).bits()) {
                alignas(64) float lanes[8][W];
                const Pack* inputs[6] = {&ax, &ay, &bx, &by, &cx, &cy};
                for (int k = 0; k < 6; ++k) inputs[k]->store(lanes[k]);
                u.store(lanes[6]);
                v.store(lanes[7]);
                alignas(64) float w_lanes[W];
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

        const Pack az = ray.sz * a_z, bz = ray.sz * b_z, cz = ray.sz * c_z;
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

    std::vector<Packet<N>> packets_;     // slots [0, half_begin_), N a packet
    std::vector<Packet<half>> halves_;   // slots from half_begin_ on, N/2 a packet
    std::vector<Vec3<Real>> normals_;    // per slot, read only when culling back faces
    std::uint32_t half_begin_ = 0;
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
