#!/usr/bin/env bash
# Builds the unit tests (and, given a regex beyond them, the prism renderer) with AddressSanitizer
# and UndefinedBehaviorSanitizer (-DPRISM_SANITIZE=ON, in build-sanitize/) and runs the unit tests
# there (ctest -R ^unit/): what CI runs sanitized. Any report fails the run. -O1 keeps the build and the run short on 2 cores.
# Choices that keep CI within its budget (docs/hostile-input.md, "Sanitizers"):
# - clang 14 compiles it (installed here when missing): the instrumented
#   build took 0.35 of GCC 12's time on test_small_scenes.cpp (75 s against 215 s of CPU);
# - forced inlining is off (PRISM_NO_FORCED_INLINE), so each kernel is instrumented once;
# - the target is x86-64-v3 (AVX2), not this machine's: under clang with AVX-512 the Pack is the
#   array form (simd/pack.hpp), whose calls, uninlined and instrumented, took the unit tests
#   twice as long to run (260 s against 133 s); with AVX2 the Pack is libstdc++'s simd, as in
#   the Release build;
# - ASan's use-after-scope check is off (it tripled the compile time of the template-heavy test
#   files under GCC);
# - Embree is left out (its library is not instrumented; prism's adapter is tested in the Release
#   suite), so unit/test_embree reports itself skipped here.
# - Ninja schedules it, not Make: Make starts a target's objects only once the targets it links
#   are built, so one core sat idle while the slowest shipped renderer compiled alone before the
#   tests, where Ninja compiles the test files beside it (two CI runs: 8 min 16 s and 9 min 49 s,
#   against Make's 9 min 51 s and 9 min 54 s, within the machine's spread).
# The test files compile in unity groups, as in the Release build (tests/CMakeLists.txt,
# PRISM_UNITY_TESTS).
#   bash tools/sanitize.sh [ctest regex, default ^unit/]
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-dependencies.sh --with-sanitizers
build=build-sanitize
# A build folder configured for another compiler (GCC, before clang built this) or another
# generator (Make, before Ninja) starts over.
if [[ -f $build/CMakeCache.txt ]] && { ! grep -q "^CMAKE_CXX_COMPILER:[A-Z]*=.*clang++-14" $build/CMakeCache.txt ||
                                       ! grep -q "^CMAKE_GENERATOR:INTERNAL=Ninja$" $build/CMakeCache.txt; }; then
  rm -rf $build
fi
if [[ ! -f $build/CMakeCache.txt ]]; then
  cmake -S . -B $build -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++-14 \
        -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1 -fno-sanitize-address-use-after-scope -march=x86-64-v3" \
        -DPRISM_NATIVE=OFF -DPRISM_SANITIZE=ON -DPRISM_WITH_EMBREE=OFF >/dev/null
fi
# The unit tests need prism_tests alone; other tests (a regex beyond ^unit/) run the sanitized
# prism too. Leaving its build out of the default run saves CI about 30 s at the end of the
# build, where one core compiles it alone.
regex=${1:-^unit/}
targets=(prism_tests)
[[ $regex == "^unit/" ]] || targets+=(prism-render)
cmake --build $build --target "${targets[@]}" -j "$(nproc)"
# halt_on_error: the first report fails its test; detect_leaks stays on (the default).
export ASAN_OPTIONS=halt_on_error=1:abort_on_error=0 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
# The path tracer's agreement test (unit/test_path_tracer_agreement: 124 renders of small
# Cornell boxes, a statistical check) runs in the Release suite alone: under the sanitizers it
# took a minute of CI's budget and reaches no code that the furnace test (every sampler and
# RendererParams combination) does not also run sanitized.
exclude=()
[[ $regex == "^unit/" ]] && exclude=(-E "^unit/test_path_tracer_agreement$")
ctest --test-dir $build -R "$regex" "${exclude[@]}" -j "$(nproc)" --output-on-failure
