// The one SIMD layer of prism: Pack<T, N>, N lanes of float or double, and its Mask. The wide
// BVH's node and leaf tests, the geometry's row tests (several rays side by side), a row's
// camera rays, and three per-point computations (a light mesh's view weights, the point lights'
// shadow lanes, an instance's ray offset) are written against it; nothing else uses intrinsics.
// Where libstdc++'s std::experimental::simd exists (GCC 11 and later, on x86-64, ARM and
// POWER), a Pack is a stdx::simd of the ABI that fits N lanes (one AVX register for 8 floats
// or 4 doubles under -mavx2, two SSE or NEON registers otherwise); elsewhere, or with
// PRISM_SIMD_SCALAR defined, it is a plain array whose loops the compiler may vectorise itself.
// Both give bit-identical results: every operation is one IEEE operation per lane, and prism
// builds with -ffp-contract=off so no compiler fuses a multiply and an add (a fused edge
// function would no longer be the exact negation of its neighbour's, and the watertight test
// would leak). See docs/accelerators.md, "The SIMD layer", for the measurements behind the choice.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <utility>

// Not under clang where AVX-512 is enabled: there libstdc++'s masks are bit masks, and clang 14
// compiles `where(mask, b) = a` into wrong lanes (every width of float and double; select and
// all built on it, seen as wrong images in the unit tests, test_simd_pack's select case).
// There the Pack is the array form, as with PRISM_SIMD_SCALAR, and computes the same bits.
#if !defined(PRISM_SIMD_SCALAR) && defined(__GLIBCXX__) && __has_include(<experimental/simd>) && \
    !(defined(__clang__) && defined(__AVX512F__))
#include <experimental/simd>
#define PRISM_SIMD_STDX 1
#endif

#if defined(PRISM_SIMD_STDX) && (defined(__x86_64__) || defined(__i386__)) && defined(__SSE2__)
#include <immintrin.h>
#define PRISM_SIMD_X86 1
#endif

// Every operation is forced inline: each is one instruction or two, and a call costs more (GCC
// left the slab test's max_keep and min_keep out of line, 3.7% of a course primary profile).
// Not in a sanitized build, for the reason PRISM_FORCE_INLINE gives (math/force_inline.hpp).
#if (defined(__GNUC__) || defined(__clang__)) && !defined(PRISM_NO_FORCED_INLINE)
#define PRISM_SIMD_INLINE [[gnu::always_inline]]
#else
#define PRISM_SIMD_INLINE
#endif

namespace prism::simd {

#ifdef PRISM_SIMD_STDX
namespace stdx = std::experimental;

template <class T, int N>
struct Mask {
    static constexpr bool split = false;
    using Native = stdx::simd_mask<T, stdx::simd_abi::deduce_t<T, N>>;
    Native native;

    PRISM_SIMD_INLINE friend Mask operator&(Mask a, Mask b) { return {a.native && b.native}; }
    PRISM_SIMD_INLINE friend Mask operator|(Mask a, Mask b) { return {a.native || b.native}; }
    PRISM_SIMD_INLINE friend Mask operator!(Mask a) { return {!a.native}; }
    PRISM_SIMD_INLINE bool any() const { return stdx::any_of(native); }
    // Lane i is bit i. __to_bitset is libstdc++'s own (a movmsk on x86).
    PRISM_SIMD_INLINE std::uint32_t bits() const { return std::uint32_t(native.__to_bitset().to_ulong()); }
};

template <class T, int N>
struct Pack {
    static constexpr bool split = false;
    using Native = stdx::simd<T, stdx::simd_abi::deduce_t<T, N>>;
    static_assert(Native::size() == std::size_t(N));
    Native native;

    PRISM_SIMD_INLINE static Pack broadcast(T value) { return {Native(value)}; }
    // Lane i is lane(i): values gathered from scalars without a trip through memory (an array
    // of them loaded made GCC 12 assemble its last two lanes in integer registers and on the
    // stack).
    template <class Lane>
    PRISM_SIMD_INLINE static Pack generate(const Lane& lane) {
        return {Native([&](auto i) { return lane(int(i)); })};
    }
    // An AVX register's load through its intrinsic: libstdc++'s load (a memcpy into the
    // vector) left GCC 12 storing some loaded packs to the stack and reading them back at once,
    // in the wide BVH's node test on the third axis's planes (a store-to-load forward on the
    // chain from a node's address to the next), 16 such pairs in the intersection benchmark and
    // 4 in `prism`. Without them, AVX2 float rays on the course mesh took about 0.83 of the
    // time (bench/RESULTS.md, "Per ray against Embree"); the same loaded bits.
    PRISM_SIMD_INLINE static Pack load(const T* values) {
#if defined(PRISM_SIMD_X86) && defined(__AVX__)
        if constexpr (std::is_same_v<T, float> && requires(const Native& v) { static_cast<__m256>(v); })
            return {Native(_mm256_loadu_ps(values))};
        else if constexpr (std::is_same_v<T, double> && requires(const Native& v) { static_cast<__m256d>(v); })
            return {Native(_mm256_loadu_pd(values))};
        else
#endif
            return {Native(values, stdx::element_aligned)};
    }
    PRISM_SIMD_INLINE void store(T* values) const { native.copy_to(values, stdx::element_aligned); }

    PRISM_SIMD_INLINE friend Pack operator+(Pack a, Pack b) { return {a.native + b.native}; }
    PRISM_SIMD_INLINE friend Pack operator-(Pack a, Pack b) { return {a.native - b.native}; }
    PRISM_SIMD_INLINE friend Pack operator*(Pack a, Pack b) { return {a.native * b.native}; }
    PRISM_SIMD_INLINE friend Pack operator/(Pack a, Pack b) { return {a.native / b.native}; }
    PRISM_SIMD_INLINE friend Pack operator-(Pack a) { return {-a.native}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator<(Pack a, Pack b) { return {a.native < b.native}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator<=(Pack a, Pack b) { return {a.native <= b.native}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator>(Pack a, Pack b) { return {a.native > b.native}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator>=(Pack a, Pack b) { return {a.native >= b.native}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator==(Pack a, Pack b) { return {a.native == b.native}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator!=(Pack a, Pack b) { return {a.native != b.native}; }
    // mask ? a : b, lane by lane.
    PRISM_SIMD_INLINE friend Pack select(Mask<T, N> mask, Pack a, Pack b) {
        stdx::where(mask.native, b.native) = a.native;
        return b;
    }
};

// More lanes than one register of the target holds (16 floats or 8 doubles under AVX2): two
// halves, each a Pack of one register, and every operation done on both. libstdc++ gives such
// a width its fixed_size ABI instead, whose masks are bitsets: every compare converted the
// lanes to bits and every select back, and on an AVX2 machine (the AMD EPYC VM, 2026-12-01) the
// dragon's rays in double, whose wide BVH tests 8 children in 8 doubles, took 3.2-4.1 times
// float's time per ray (bench/RESULTS.md, "Per ray against Embree"). The same IEEE operation
// per lane either way, so the same bits.
template <class T, int N>
inline constexpr bool needs_halves =
    N % 2 == 0 && std::is_same_v<stdx::simd_abi::deduce_t<T, N>, stdx::simd_abi::fixed_size<N>>;

template <class T, int N>
    requires needs_halves<T, N>
struct Mask<T, N> {
    static constexpr bool split = true;
    Mask<T, N / 2> low, high;  // lanes [0, N/2) and [N/2, N)

    PRISM_SIMD_INLINE friend Mask operator&(Mask a, Mask b) { return {a.low & b.low, a.high & b.high}; }
    PRISM_SIMD_INLINE friend Mask operator|(Mask a, Mask b) { return {a.low | b.low, a.high | b.high}; }
    PRISM_SIMD_INLINE friend Mask operator!(Mask a) { return {!a.low, !a.high}; }
    PRISM_SIMD_INLINE bool any() const { return (low | high).any(); }
    PRISM_SIMD_INLINE std::uint32_t bits() const { return low.bits() | high.bits() << (N / 2); }
};

template <class T, int N>
    requires needs_halves<T, N>
struct Pack<T, N> {
    static constexpr bool split = true;
    using Half = Pack<T, N / 2>;
    Half low, high;  // lanes [0, N/2) and [N/2, N)

    PRISM_SIMD_INLINE static Pack broadcast(T value) { return {Half::broadcast(value), Half::broadcast(value)}; }
    template <class Lane>
    PRISM_SIMD_INLINE static Pack generate(const Lane& lane) {
        return {Half::generate(lane), Half::generate([&](int i) { return lane(i + N / 2); })};
    }
    PRISM_SIMD_INLINE static Pack load(const T* values) { return {Half::load(values), Half::load(values + N / 2)}; }
    PRISM_SIMD_INLINE void store(T* values) const {
        low.store(values);
        high.store(values + N / 2);
    }

    PRISM_SIMD_INLINE friend Pack operator+(Pack a, Pack b) { return {a.low + b.low, a.high + b.high}; }
    PRISM_SIMD_INLINE friend Pack operator-(Pack a, Pack b) { return {a.low - b.low, a.high - b.high}; }
    PRISM_SIMD_INLINE friend Pack operator*(Pack a, Pack b) { return {a.low * b.low, a.high * b.high}; }
    PRISM_SIMD_INLINE friend Pack operator/(Pack a, Pack b) { return {a.low / b.low, a.high / b.high}; }
    PRISM_SIMD_INLINE friend Pack operator-(Pack a) { return {-a.low, -a.high}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator<(Pack a, Pack b) { return {a.low < b.low, a.high < b.high}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator<=(Pack a, Pack b) { return {a.low <= b.low, a.high <= b.high}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator>(Pack a, Pack b) { return {a.low > b.low, a.high > b.high}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator>=(Pack a, Pack b) { return {a.low >= b.low, a.high >= b.high}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator==(Pack a, Pack b) { return {a.low == b.low, a.high == b.high}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator!=(Pack a, Pack b) { return {a.low != b.low, a.high != b.high}; }
    PRISM_SIMD_INLINE friend Pack select(Mask<T, N> mask, Pack a, Pack b) {
        return {select(mask.low, a.low, b.low), select(mask.high, a.high, b.high)};
    }
};

#ifdef PRISM_SIMD_X86
// The x86 instructions a Pack may use directly, where its native simd is one register: the
// register type it converts to names the instruction; another width, or a Pack split over two
// registers, converts to none and keeps the portable form. (The register types are named in
// requires-expressions, not as template arguments, which would drop their attributes.)
namespace x86 {
#define PRISM_SIMD_HOLDS(register_type) requires(const V& v) { static_cast<register_type>(v); }
#define PRISM_SIMD_MIN_MAX(register_type, max_instruction, min_instruction)                                        \
    if constexpr (PRISM_SIMD_HOLDS(register_type)) {                                                                \
        const register_type x = static_cast<register_type>(a), y = static_cast<register_type>(b);                  \
        return V(maximum ? max_instruction(x, y) : min_instruction(x, y));                                         \
    }

#ifdef __AVX512F__
// The 512-bit forms through their masked intrinsics, every lane selected: GCC 12's unmasked
// ones start from an undefined register and warn of it under -Wall (GCC bug 105593).
PRISM_SIMD_INLINE inline __m512 masked_max_ps(__m512 x, __m512 y) { return _mm512_mask_max_ps(x, __mmask16(-1), x, y); }
PRISM_SIMD_INLINE inline __m512 masked_min_ps(__m512 x, __m512 y) { return _mm512_mask_min_ps(x, __mmask16(-1), x, y); }
PRISM_SIMD_INLINE inline __m512d masked_max_pd(__m512d x, __m512d y) { return _mm512_mask_max_pd(x, __mmask8(-1), x, y); }
PRISM_SIMD_INLINE inline __m512d masked_min_pd(__m512d x, __m512d y) { return _mm512_mask_min_pd(x, __mmask8(-1), x, y); }
#endif

// maxps(a, b) = a > b ? a : b and minps(a, b) = a < b ? a : b (pd for double); void where V
// is no one register.
template <bool maximum, class T, class V>
PRISM_SIMD_INLINE inline auto min_max(const V& a, const V& b) {
    if constexpr (std::is_same_v<T, float>) {
        PRISM_SIMD_MIN_MAX(__m128, _mm_max_ps, _mm_min_ps)
#ifdef __AVX__
        else PRISM_SIMD_MIN_MAX(__m256, _mm256_max_ps, _mm256_min_ps)
#endif
#ifdef __AVX512F__
        else PRISM_SIMD_MIN_MAX(__m512, masked_max_ps, masked_min_ps)
#endif
    } else if constexpr (std::is_same_v<T, double>) {
        PRISM_SIMD_MIN_MAX(__m128d, _mm_max_pd, _mm_min_pd)
#ifdef __AVX__
        else PRISM_SIMD_MIN_MAX(__m256d, _mm256_max_pd, _mm256_min_pd)
#endif
#ifdef __AVX512F__
        else PRISM_SIMD_MIN_MAX(__m512d, masked_max_pd, masked_min_pd)
#endif
    }
}
#undef PRISM_SIMD_MIN_MAX
#undef PRISM_SIMD_HOLDS

template <class T, class V>
constexpr bool has_min_max = !std::is_void_v<decltype(min_max<true, T>(std::declval<const V&>(), std::declval<const V&>()))>;

}  // namespace x86
#endif

#else

template <class T, int N>
struct Mask {
    std::array<bool, N> lanes;

    PRISM_SIMD_INLINE friend Mask operator&(Mask a, Mask b) { return combine(a, b, [](bool x, bool y) { return x && y; }); }
    PRISM_SIMD_INLINE friend Mask operator|(Mask a, Mask b) { return combine(a, b, [](bool x, bool y) { return x || y; }); }
    PRISM_SIMD_INLINE friend Mask operator!(Mask a) {
        for (bool& lane : a.lanes) lane = !lane;
        return a;
    }
    PRISM_SIMD_INLINE bool any() const { return bits() != 0; }
    PRISM_SIMD_INLINE std::uint32_t bits() const {
        std::uint32_t result = 0;
        for (int i = 0; i < N; ++i) result |= std::uint32_t(lanes[i]) << i;
        return result;
    }

private:
    template <class Op>
    static Mask combine(Mask a, const Mask& b, Op op) {
        for (int i = 0; i < N; ++i) a.lanes[i] = op(a.lanes[i], b.lanes[i]);
        return a;
    }
};

template <class T, int N>
struct Pack {
    static constexpr bool split = false;
    std::array<T, N> lanes;

    PRISM_SIMD_INLINE static Pack broadcast(T value) {
        Pack result;
        result.lanes.fill(value);
        return result;
    }
    template <class Lane>
    PRISM_SIMD_INLINE static Pack generate(const Lane& lane) {
        Pack result;
        for (int i = 0; i < N; ++i) result.lanes[i] = lane(i);
        return result;
    }
    PRISM_SIMD_INLINE static Pack load(const T* values) {
        Pack result;
        for (int i = 0; i < N; ++i) result.lanes[i] = values[i];
        return result;
    }
    PRISM_SIMD_INLINE void store(T* values) const {
        for (int i = 0; i < N; ++i) values[i] = lanes[i];
    }

    PRISM_SIMD_INLINE friend Pack operator+(Pack a, Pack b) { return map(a, b, [](T x, T y) { return x + y; }); }
    PRISM_SIMD_INLINE friend Pack operator-(Pack a, Pack b) { return map(a, b, [](T x, T y) { return x - y; }); }
    PRISM_SIMD_INLINE friend Pack operator*(Pack a, Pack b) { return map(a, b, [](T x, T y) { return x * y; }); }
    PRISM_SIMD_INLINE friend Pack operator/(Pack a, Pack b) { return map(a, b, [](T x, T y) { return x / y; }); }
    PRISM_SIMD_INLINE friend Pack operator-(Pack a) {
        for (T& lane : a.lanes) lane = -lane;
        return a;
    }
    PRISM_SIMD_INLINE friend Mask<T, N> operator<(Pack a, Pack b) { return compare(a, b, [](T x, T y) { return x < y; }); }
    PRISM_SIMD_INLINE friend Mask<T, N> operator<=(Pack a, Pack b) { return compare(a, b, [](T x, T y) { return x <= y; }); }
    PRISM_SIMD_INLINE friend Mask<T, N> operator>(Pack a, Pack b) { return compare(a, b, [](T x, T y) { return x > y; }); }
    PRISM_SIMD_INLINE friend Mask<T, N> operator>=(Pack a, Pack b) { return compare(a, b, [](T x, T y) { return x >= y; }); }
    PRISM_SIMD_INLINE friend Mask<T, N> operator==(Pack a, Pack b) { return compare(a, b, [](T x, T y) { return x == y; }); }
    PRISM_SIMD_INLINE friend Mask<T, N> operator!=(Pack a, Pack b) { return compare(a, b, [](T x, T y) { return x != y; }); }
    PRISM_SIMD_INLINE friend Pack select(Mask<T, N> mask, Pack a, Pack b) {
        for (int i = 0; i < N; ++i) b.lanes[i] = mask.lanes[i] ? a.lanes[i] : b.lanes[i];
        return b;
    }

private:
    template <class Op>
    static Pack map(Pack a, const Pack& b, Op op) {
        for (int i = 0; i < N; ++i) a.lanes[i] = op(a.lanes[i], b.lanes[i]);
        return a;
    }
    template <class Op>
    static Mask<T, N> compare(const Pack& a, const Pack& b, Op op) {
        Mask<T, N> result;
        for (int i = 0; i < N; ++i) result.lanes[i] = op(a.lanes[i], b.lanes[i]);
        return result;
    }
};

#endif

// a > b ? a : b and a < b ? a : b, lane by lane: a NaN in `a` leaves `b`, which is what the
// slab test needs (a NaN slab distance, 0 * inf on a slab plane, constrains nothing).
// x86's maxps and minps are exactly these (either operand NaN, or both zero: the second), in
// one instruction; GCC compiles the select into a compare and a blend instead, and the slab
// test chains three of them from a node's load to its mask. Where the Pack is one x86 register
// its own instruction is used; elsewhere the select.
template <class T, int N>
PRISM_SIMD_INLINE inline Pack<T, N> max_keep(Pack<T, N> a, Pack<T, N> b) {
    if constexpr (Pack<T, N>::split) return {max_keep(a.low, b.low), max_keep(a.high, b.high)};
#if defined(PRISM_SIMD_STDX) && defined(PRISM_SIMD_X86)
    else if constexpr (x86::has_min_max<T, typename Pack<T, N>::Native>) return {x86::min_max<true, T>(a.native, b.native)};
#endif
    else return select(a > b, a, b);
}
template <class T, int N>
PRISM_SIMD_INLINE inline Pack<T, N> min_keep(Pack<T, N> a, Pack<T, N> b) {
    if constexpr (Pack<T, N>::split) return {min_keep(a.low, b.low), min_keep(a.high, b.high)};
#if defined(PRISM_SIMD_STDX) && defined(PRISM_SIMD_X86)
    else if constexpr (x86::has_min_max<T, typename Pack<T, N>::Native>) return {x86::min_max<false, T>(a.native, b.native)};
#endif
    else return select(a < b, a, b);
}

// The correctly rounded square root, lane by lane: std::sqrt's bits. The 512-bit forms through
// their masked intrinsics, as masked_max_ps above (GCC bug 105593).
template <class T, int N>
PRISM_SIMD_INLINE inline Pack<T, N> sqrt(Pack<T, N> a) {
#if defined(PRISM_SIMD_STDX)
    if constexpr (Pack<T, N>::split) {
        return {sqrt(a.low), sqrt(a.high)};
    } else {
#if defined(PRISM_SIMD_X86) && defined(__AVX512F__)
        using Native = typename Pack<T, N>::Native;
        if constexpr (std::is_same_v<T, float> && requires(const Native& v) { static_cast<__m512>(v); }) {
            const __m512 x = static_cast<__m512>(a.native);
            return {Native(_mm512_mask_sqrt_ps(x, __mmask16(-1), x))};
        } else if constexpr (std::is_same_v<T, double> && requires(const Native& v) { static_cast<__m512d>(v); }) {
            const __m512d x = static_cast<__m512d>(a.native);
            return {Native(_mm512_mask_sqrt_pd(x, __mmask8(-1), x))};
        } else
#endif
            return {stdx::sqrt(a.native)};
    }
#else
    for (T& lane : a.lanes) lane = std::sqrt(lane);
    return a;
#endif
}

// N rows of N values, each row where rows[i] points, as N packs: columns[j]'s lane i is
// rows[i][j] (the rays of a row of lanes, each stored whole, as the lanes' origins, directions
// and bounds). Filled lane by lane through memory, a pack is loaded from N stores made just
// before it, which a load cannot take from the store buffer: it waits for all of them to reach
// the cache, and the lanes' ray set-up (TrianglePackets::RayLanes) stalled there for 10% of a
// multi-sample Cornell box's time. Where 8 floats are one AVX register, each row is loaded
// whole and the 8 x 8 block transposed in registers (unpacks, shuffles and lane permutes);
// elsewhere the lanes are filled one by one. The same values either way.
template <class T, int N>
PRISM_SIMD_INLINE inline void load_transposed(const T* const* rows, Pack<T, N>* columns) {
#if defined(PRISM_SIMD_STDX) && defined(PRISM_SIMD_X86) && defined(__AVX__)
    if constexpr (std::is_same_v<T, float> && N == 8 && !Pack<T, N>::split) {
        using Native = typename Pack<T, N>::Native;
        if constexpr (requires(const Native& v) { static_cast<__m256>(v); }) {
            __m256 r[8];
            for (int i = 0; i < 8; ++i) r[i] = _mm256_loadu_ps(rows[i]);
            // Pairs of rows interleaved, then quadruples, then the 128-bit halves exchanged.
            const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
            const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
            const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
            const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
            const __m256 u0 = _mm256_shuffle_ps(t0, t2, 0x44), u1 = _mm256_shuffle_ps(t0, t2, 0xee);
            const __m256 u2 = _mm256_shuffle_ps(t1, t3, 0x44), u3 = _mm256_shuffle_ps(t1, t3, 0xee);
            const __m256 u4 = _mm256_shuffle_ps(t4, t6, 0x44), u5 = _mm256_shuffle_ps(t4, t6, 0xee);
            const __m256 u6 = _mm256_shuffle_ps(t5, t7, 0x44), u7 = _mm256_shuffle_ps(t5, t7, 0xee);
            columns[0] = {Native(_mm256_permute2f128_ps(u0, u4, 0x20))};
            columns[1] = {Native(_mm256_permute2f128_ps(u1, u5, 0x20))};
            columns[2] = {Native(_mm256_permute2f128_ps(u2, u6, 0x20))};
            columns[3] = {Native(_mm256_permute2f128_ps(u3, u7, 0x20))};
            columns[4] = {Native(_mm256_permute2f128_ps(u0, u4, 0x31))};
            columns[5] = {Native(_mm256_permute2f128_ps(u1, u5, 0x31))};
            columns[6] = {Native(_mm256_permute2f128_ps(u2, u6, 0x31))};
            columns[7] = {Native(_mm256_permute2f128_ps(u3, u7, 0x31))};
            return;
        }
    }
#endif
    alignas(64) T lanes[N][N];
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) lanes[j][i] = rows[i][j];
    for (int j = 0; j < N; ++j) columns[j] = Pack<T, N>::load(lanes[j]);
}

}  // namespace prism::simd
