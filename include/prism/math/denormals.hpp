// Subnormal numbers read and written as zero while a render's work runs: the x86 MXCSR's
// denormals-are-zero (DAZ) and flush-to-zero (FTZ) bits, set for a scope and restored after it,
// as Embree sets them around its own scene builds and asks its callers to set them around its
// traversal.
//
// Why prism needs them: GCC computes a Vec3 in a 4-lane register, and where it loads the three
// floats from the stack the fourth lane is whatever the stack held there. When that is an
// integer a sampler left behind (a ZSobol block's point bits, say), the lane reads as a
// subnormal float, and on Intel cores a multiplication or division with a subnormal operand
// takes a microcode assist: 37 ns against under 1 ns for the same operation on normal numbers
// (measured on this project's Xeon VM). On hw7 path_glass with the sobol sampler such lanes
// cost 4% of the render (paired; perf puts most of it in the BRDF's kd / pi), with independent
// samples about 1%.
// The lane's value is never used; only its time is.
//
// What it changes in results: a value below 2^-126 (float) or 2^-1022 (double) becomes zero where
// IEEE arithmetic keeps it. Radiance, distances and error bounds of a scene at any sane scale are
// far above that: every course scene but hw7 path_glass renders byte for byte as without it
// (hw1-hw2 in float and double; hw3-hw7 at reduced settings). The path tracer compares throughputs
// and densities with zero, and a path whose weight has sunk below the smallest normal number now
// ends where it went on carrying next to nothing; with the independent sampler the pixel's later
// samples then draw other numbers. So five of hw7 path_glass's nine images differ, in 1 to 289 of
// their 16,384 pixels at a quarter scale and 16 samples, within the noise (bench/RESULTS.md,
// "Subnormal fourth lanes"). The consumer's own code is not affected: the bits are restored when
// the scope ends, and the Renderer ends it before calling back into the consumer (on_tile).
#pragma once

#if defined(__SSE__) || defined(_M_X64)
#include <xmmintrin.h>
#define PRISM_HAS_MXCSR 1
#endif

namespace prism {

class FlushDenormals {
public:
#ifdef PRISM_HAS_MXCSR
    FlushDenormals() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | flush_to_zero | denormals_are_zero); }
    ~FlushDenormals() { _mm_setcsr(saved_); }
#else
    FlushDenormals() = default;  // other targets keep IEEE subnormals (and their speed)
#endif
    FlushDenormals(const FlushDenormals&) = delete;
    FlushDenormals& operator=(const FlushDenormals&) = delete;

private:
#ifdef PRISM_HAS_MXCSR
    static constexpr unsigned flush_to_zero = 1u << 15, denormals_are_zero = 1u << 6;
    unsigned saved_;
#endif
};

}  // namespace prism
