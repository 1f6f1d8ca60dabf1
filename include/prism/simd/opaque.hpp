// A value the compiler must take as it is, in a register, without knowing what it holds: an
// empty asm statement that claims to change it. Used on values that are loop invariant but
// should not be combined with constants ahead of the loop. GCC turns each sum of an invariant
// and a constant displacement into an invariant of its own; a leaf's nine packet rows, three
// per-ray offsets plus three displacements, became nine offsets held across the packet loop,
// more than the free general registers, and were spilled to vector registers and moved back
// before each load. An opaque offset is used as it is, with the displacement in the load.
// A no-op where the compiler has no GNU asm.
#pragma once

namespace prism::simd {

template <class T>
[[gnu::always_inline]] inline T opaque(T value) {
#if defined(__GNUC__) || defined(__clang__)
    asm("" : "+r"(value));
#endif
    return value;
}

}  // namespace prism::simd
