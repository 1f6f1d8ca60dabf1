#!/usr/bin/env bash
# Builds the unit tests and the prism renderer with AddressSanitizer and UndefinedBehaviorSanitizer
# (-DPRISM_SANITIZE=ON, in build-sanitize/) and runs the unit tests there (ctest -R ^unit/): what
# CI runs sanitized. Any report fails the run. -O1 keeps the build and the run short on 2 cores.
#   bash tools/sanitize.sh [ctest regex, default ^unit/]
set -euo pipefail
cd "$(dirname "$0")/.."
build=build-sanitize
if [[ ! -f $build/CMakeCache.txt ]]; then
  cmake -S . -B $build -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" -DPRISM_SANITIZE=ON >/dev/null
fi
cmake --build $build --target prism_tests prism-render -j "$(nproc)"
# halt_on_error: the first report fails its test; detect_leaks stays on (the default).
export ASAN_OPTIONS=halt_on_error=1:abort_on_error=0 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
ctest --test-dir $build -R "${1:-^unit/}" -j "$(nproc)" --output-on-failure
