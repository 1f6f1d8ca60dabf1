// A hint that an object is about to be read: every 64-byte cache line it spans is requested
// now, so the wait for memory overlaps other work. The wide BVH's traversal is bound by that
// wait: in a dragon primary profile, the first load of a node and of a leaf's triangle packet
// took most of their functions' samples. A no-op where the compiler has no prefetch builtin.
#pragma once

#include <cstddef>

namespace prism::simd {

inline constexpr std::size_t cache_line_bytes = 64;

// For a function, or a lambda (after its parameters), whose only effect is a prefetch, such as a
// traversal's `touch` callback: GCC counts __builtin_prefetch as no side effect, finds such a
// function const when it keeps it out of line, and then deletes every call to it. The wide BVH's
// leaf prefetch had been compiled away ever since it was written; forced inline, it is issued.
#if defined(__GNUC__) || defined(__clang__)
#define PRISM_PREFETCH_INLINE __attribute__((always_inline))
#else
#define PRISM_PREFETCH_INLINE
#endif

template <class T>
[[gnu::always_inline]] inline void prefetch(const T& object) {
#if defined(__GNUC__) || defined(__clang__)
    const char* bytes = reinterpret_cast<const char*>(&object);
    for (std::size_t offset = 0; offset < sizeof(T); offset += cache_line_bytes) __builtin_prefetch(bytes + offset);
#else
    (void)object;
#endif
}

}  // namespace prism::simd
