// PRISM_FORCE_INLINE: a function inlined into every caller, whatever the compiler's inliner would
// decide. The traversal kernels, the packet tests and their small helpers carry it: GCC left some
// of them out of line in the inner loops, where the call cost more than the work.
//
// It is a speed choice of optimized builds, and nothing depends on it for what it computes. A
// sanitized build (PRISM_SANITIZE, which defines PRISM_NO_FORCED_INLINE) instruments each such
// function once instead of at each of its call sites: forced, the sanitized unit tests took more
// than twice the compile time (clang 14, ASan + UBSan at -O1, test_shadow_lanes.cpp 239 s against
// 107 s of CPU), which kept CI over its budget.
//
// GNU attribute syntax, so that one spelling serves functions and lambdas alike (a standard
// attribute after a lambda's parameters belongs to its type, where always_inline means nothing).
#pragma once

#if (defined(__GNUC__) || defined(__clang__)) && !defined(PRISM_NO_FORCED_INLINE)
#define PRISM_FORCE_INLINE __attribute__((always_inline))
#else
#define PRISM_FORCE_INLINE
#endif
