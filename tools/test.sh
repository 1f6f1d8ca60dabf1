#!/usr/bin/env bash
# The README's second command (and CI's): install what is missing, build everything in Release,
# and run the whole test suite with ctest: unit tests, bad-input tests, the course regression
# and the installed-package consumer.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-dependencies.sh
# Every option the tests need is set here, not inherited: the build folder is shared with
# tools/render-default.sh, and a cache left by another command must not turn the tests off.
bash tools/configure-build.sh -DPRISM_BUILD_EXAMPLES=ON -DPRISM_BUILD_TESTS=ON
cmake --build build -j "$(nproc)"
# --no-tests=error: a run that finds no test fails, instead of passing without testing.
ctest --test-dir build --output-on-failure --no-tests=error -j "$(nproc)" "$@"
