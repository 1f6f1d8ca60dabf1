// A mesh's triangles packed N at a time, SoA, for the wide BVH's leaves, and the watertight
// test (geometry/watertight.hpp, Woop, Benthin, Wald 2013) run on a whole packet with one SIMD
// instruction stream (simd/pack.hpp). It computes every lane with the scalar test's operations
// in the scalar test's order, so each lane's edge functions, t and barycentrics are the scalar
// test's bits; the lanes that pass are then accepted one by one in slot order against the
// shrinking t_max, exactly as the scalar leaf loop does. The packed test is therefore as
// watertight as the scalar one and picks the same triangle on every tie.
// DoubleRefine runs the same test on packets of double vertices under float traversal. Every
// double packet (DoubleRefine's, Watertight's in a double tree) is first passed through a float
// filter (below) that skips the packets whose every lane it proves a miss of the double test.
#pragma once

#include <prism/geometry/double_refine.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/watertight.hpp>
#include <prism/math/floating_point.hpp>
#include <prism/simd/pack.hpp>
#include <prism/simd/prefetch.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <concepts>
#include <cstdint>
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
    // Double packets (DoubleRefine's, and Watertight's in a double tree) are filtered in float
    // before the double test (filter below).
    static constexpr bool filtered = std::is_same_v<Storage, double>;

private:
    using FilterPack = simd::Pack<float, N>;
    // The filter's ray: the double test's origin and shear rounded to float, and a bound on the
    // origin's coordinates (filter below).
    struct FilterRay {
        FilterPack origin[3];
        FilterPack sx, sy, magnitude;
    };
    struct NoFilterRay {};

public:
    // What the packed test needs of a ray, broadcast once per ray.
    struct PackedRay {
        int kx, ky, kz;
        Pack origin[3];
        Pack sx, sy, sz;
        [[no_unique_address]] std::conditional_t<filtered, FilterRay, NoFilterRay> filter;
        explicit PackedRay(const Prepared& prepared) {
            const Watertight::Prepared<Storage>& ray = watertight_ray(prepared);
            kx = ray.kx;
            ky = ray.ky;
            kz = ray.kz;
            for (int axis = 0; axis < 3; ++axis) origin[axis] = Pack::broadcast(ray.origin[axis]);
            sx = Pack::broadcast(ray.sx);
            sy = Pack::broadcast(ray.sy);
            sz = Pack::broadcast(ray.sz);
            if constexpr (filtered) {
                float magnitude = 0;
                for (int axis = 0; axis < 3; ++axis) {
                    const float o = float(ray.origin[axis]);
                    filter.origin[axis] = FilterPack::broadcast(o);
                    magnitude = std::max(magnitude, std::abs(o));
                }
                filter.sx = FilterPack::broadcast(float(ray.sx));
                filter.sy = FilterPack::broadcast(float(ray.sy));
                filter.magnitude = FilterPack::broadcast(magnitude);
            }
        }
    };

    TrianglePackets() = default;

    // `triangles` in slot order, a multiple of N of them (the wide BVH pads its leaves).
    explicit TrianglePackets(const std::vector<std::array<Vec3<Storage>, 3>>& triangles) {
        packets_.resize(triangles.size() / N);
        normals_.resize(triangles.size());
        for (std::size_t slot = 0; slot < triangles.size(); ++slot) {
            Packet& packet = packets_[slot / N];
            const auto& p = triangles[slot];
            for (int vertex = 0; vertex < 3; ++vertex)
                for (int axis = 0; axis < 3; ++axis) packet.vertices[vertex][axis][slot % N] = p[vertex][axis];
            // The back-face test's normal, rounded as TriangleMesh's scalar loop rounds it.
            normals_[slot] = Vec3<Real>(glm::cross(p[1] - p[0], p[2] - p[0]));
        }
        if constexpr (filtered) {
            filters_.resize(packets_.size());
            for (std::size_t slot = 0; slot < triangles.size(); ++slot) {
                FilterPacket& packet = filters_[slot / N];
                double magnitude = 0;
                for (int vertex = 0; vertex < 3; ++vertex)
                    for (int axis = 0; axis < 3; ++axis) {
                        const double coordinate = double(triangles[slot][vertex][axis]);
                        packet.vertices[vertex][axis][slot % N] = float(coordinate);
                        magnitude = std::max(magnitude, std::abs(coordinate));
                    }
                // Rounded up: W must bound every |p| (inf beyond float's range, or for a NaN
                // vertex: the filter then proves nothing about the lane).
                const float rounded = float(magnitude);
                packet.magnitude[slot % N] = std::isnan(magnitude)            ? infinity<float>
                                             : double(rounded) < magnitude ? next_up(rounded)
                                                                           : rounded;
            }
        }
    }

    std::size_t memory_bytes() const {
        return packets_.capacity() * sizeof(Packet) + normals_.capacity() * sizeof(Vec3<Real>) +
               filters_.capacity() * sizeof(FilterPacket);
    }

    // Closest hit among slots [first, first + count) (first a multiple of N); lowers t_limit.
    // Forced inline into the traversal's leaf callback, as is `test`: GCC had kept it a function
    // of its own (26% of a dragon primary profile), called once per leaf.
    template <bool CullBackfaces>
    [[gnu::always_inline]] bool intersect(const PackedRay& ray, const Vec3<Real>& direction, std::uint32_t first, std::uint32_t count,
                   Real t_min, Real& t_limit, Hit<Real>& hit) const {
        bool found = false;
        for (std::uint32_t base = first; base < first + count; base += N) {
            if constexpr (filtered) {
                // The double packet is requested before the filter runs: where the filter keeps
                // a lane, its wait overlaps the filter's instead of following it.
                simd::prefetch(packets_[base / N]);
                if ((filter(filters_[base / N], ray) & lane_mask(first + count - base)) == 0) continue;
            }
            alignas(64) Storage t[N], b1[N], b2[N];
            std::uint32_t lanes = test(packets_[base / N], ray, Storage(t_min), Storage(t_limit), t, b1, b2);
            lanes &= lane_mask(first + count - base);
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
        }
        return found;
    }

    // Requests the packet that holds slot `first` (a leaf's first slot) from memory, and for a
    // double packet the filter's copy too.
    void prefetch(std::uint32_t first) const {
        if constexpr (filtered) simd::prefetch(filters_[first / N]);
        simd::prefetch(packets_[first / N]);
    }

    // For tests of the filter: the lanes of the packet holding slot `first` that the filter
    // leaves to the double test, and the lanes the double test accepts with t anywhere in
    // (t_min, t_max]. Every lane of the second is in the first.
    std::uint32_t filter_lanes(const PackedRay& ray, std::uint32_t first) const
        requires filtered
    {
        return filter(filters_[first / N], ray);
    }
    std::uint32_t test_lanes(const PackedRay& ray, std::uint32_t first, Storage t_min, Storage t_max) const {
        alignas(64) Storage t[N], b1[N], b2[N];
        return test(packets_[first / N], ray, t_min, t_max, t, b1, b2);
    }

    // Whether any of slots [first, first + count) is hit in (t_min, t_limit).
    [[gnu::always_inline]] bool occluded(const PackedRay& ray, std::uint32_t first, std::uint32_t count, Real t_min, Real t_limit) const {
        for (std::uint32_t base = first; base < first + count; base += N) {
            if constexpr (filtered) {
                // The double packet is requested before the filter runs: where the filter keeps
                // a lane, its wait overlaps the filter's instead of following it.
                simd::prefetch(packets_[base / N]);
                if ((filter(filters_[base / N], ray) & lane_mask(first + count - base)) == 0) continue;
            }
            alignas(64) Storage t[N], b1[N], b2[N];
            std::uint32_t lanes = test(packets_[base / N], ray, Storage(t_min), Storage(t_limit), t, b1, b2);
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
    struct alignas(64) Packet {
        Storage vertices[3][3][N];  // [vertex][axis][lane]
    };

    // The filter's copy of a double packet: its vertices rounded to nearest float, and
    // per lane W >= max |p| over the lane's nine coordinates. 40 bytes per triangle beside the
    // double packet's 72.
    struct alignas(64) FilterPacket {
        float vertices[3][3][N];
        float magnitude[N];
    };

    // The lanes a double packet's test may accept; a lane left out is one the
    // double test (below, on the double vertices) provably rejects as outside the triangle.
    // It runs the watertight edge functions in float on the float-rounded vertices and
    // rejects a lane only where one edge function is below -E and another above E, E bounding
    // the float value's distance from the double test's value. Why E suffices: write p for a
    // double vertex, o for the double ray origin, s for the double shear constant (|s| <= 1, as
    // kz is the direction's largest axis), and X = (p_x - o_x) - s (p_z - o_z) in exact
    // arithmetic; u_f = 2^-24, W >= |p| and O >= |o| per coordinate (O from the float-rounded
    // origin; the slack below covers its half ulp), D = W + O.
    // - A float vertex value x~ = fl(fl(p~_x - o~_x) - fl(s~ fl(p~_z - o~_z))), with p~, o~, s~
    //   p, o, s rounded to nearest (relative error <= u_f each): its exact counterpart on the
    //   rounded inputs is within u_f (|p_x| + |p_z| + |p_z - o_z| + |o_x| + |o_z|) <= 3 u_f D of
    //   X, and the three roundings add at most gamma(3) (|p~_x - o~_x| + |p~_z - o~_z|) <=
    //   6.01 u_f D. So |x~ - X| <= delta_f = 9.01 u_f D (Higham's gamma(n), pbrt-v4 6.8).
    // - An edge function u~ = fl(fl(c~x b~y) - fl(c~y b~x)) against U = Cx By - Cy Bx, with M
    //   the largest of the lane's six |x~|: |u~ - U| <= delta_f (|c~x| + |b~y| + |c~y| + |b~x|)
    //   + 2 delta_f^2 + gamma(2) (|c~x b~y| + |c~y b~x|) <= 4 delta_f M + 2 delta_f^2 + 4.01 u_f M^2.
    // - The double test's u (Watertight in double, no rounded inputs) is within 4 delta_d M' +
    //   2 delta_d^2 + 4.01 u_d M'^2 of U, delta_d = 6.01 u_d D, M' = M + delta_f + delta_d:
    //   below 2^-25 of the float terms, inside the slack.
    // E = 4 delta M + 2 delta^2 + 6 u_f M^2 with delta = 12 u_f D: the float bound's coefficients
    // with at least 1.33x slack, which covers the double test's terms and the dozen float
    // roundings of E's own computation (each at most 1 + u_f). Where a value is subnormal the
    // relative bounds fail by at most 2^-149 per operation, so delta gains 2^-126 and E 2^-120.
    // If u~ < -E then U < -E_d and the double test's u < 0; if v~ > E, its v > 0: outside.
    // Inf or NaN anywhere makes E or the edge function inf or NaN, and no comparison rejects.
    // tests/test_double_filter.cpp runs both on millions of rays through tiny triangles' edges.
    [[gnu::always_inline]] static std::uint32_t filter(const FilterPacket& packet, const PackedRay& ray)
        requires filtered
    {
        using F = FilterPack;
        const FilterRay& f = ray.filter;
        const auto relative = [&](int vertex, int axis) {
            return F::load(packet.vertices[vertex][axis]) - f.origin[axis];
        };
        const F a_z = relative(0, ray.kz), b_z = relative(1, ray.kz), c_z = relative(2, ray.kz);
        const F ax = relative(0, ray.kx) - f.sx * a_z;
        const F ay = relative(0, ray.ky) - f.sy * a_z;
        const F bx = relative(1, ray.kx) - f.sx * b_z;
        const F by = relative(1, ray.ky) - f.sy * b_z;
        const F cx = relative(2, ray.kx) - f.sx * c_z;
        const F cy = relative(2, ray.ky) - f.sy * c_z;
        const F u = cx * by - cy * bx;
        const F v = ax * cy - ay * cx;
        const F w = bx * ay - by * ax;
        using simd::abs;
        const auto max = [](F a, F b) { return simd::max_keep(a, b); };
        const F m = max(max(max(abs(ax), abs(ay)), max(abs(bx), abs(by))), max(abs(cx), abs(cy)));
        const F d = F::load(packet.magnitude) + f.magnitude;
        const F delta = d * F::broadcast(12 * unit_roundoff<float>) + F::broadcast(0x1p-126f);
        const F bound = F::broadcast(4) * delta * m + F::broadcast(2) * delta * delta +
                        F::broadcast(6 * unit_roundoff<float>) * m * m + F::broadcast(0x1p-120f);
        const F negative_bound = F::broadcast(0) - bound;
        const auto below = (u < negative_bound) | (v < negative_bound) | (w < negative_bound);
        const auto above = (u > bound) | (v > bound) | (w > bound);
        return (~(below & above).bits()) & ((std::uint32_t(1) << N) - 1);
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

    // Watertight::intersect on every lane: the lanes hit in (t_min, t_max], with their t and
    // barycentrics stored. Same operations, same order, so the same bits as the scalar test.
    [[gnu::always_inline]] static std::uint32_t test(const Packet& packet, const PackedRay& ray, Storage t_min, Storage t_max,
                              Storage* t_out, Storage* b1_out, Storage* b2_out) {
        const auto relative = [&](int vertex, int axis) {
            return Pack::load(packet.vertices[vertex][axis]) - ray.origin[axis];
        };
        const Pack a_z = relative(0, ray.kz), b_z = relative(1, ray.kz), c_z = relative(2, ray.kz);
        const Pack ax = relative(0, ray.kx) - ray.sx * a_z;
        const Pack ay = relative(0, ray.ky) - ray.sy * a_z;
        const Pack bx = relative(1, ray.kx) - ray.sx * b_z;
        const Pack by = relative(1, ray.ky) - ray.sy * b_z;
        const Pack cx = relative(2, ray.kx) - ray.sx * c_z;
        const Pack cy = relative(2, ray.ky) - ray.sy * c_z;

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

    std::vector<Packet> packets_;
    std::vector<Vec3<Real>> normals_;        // per slot, read only when culling back faces
    std::vector<FilterPacket> filters_;      // double packets only: one per packet
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
