#!/usr/bin/env bash
# The README's second command (and CI's): install what is missing, build everything in Release,
# and run the whole test suite with ctest: unit tests, bad-input tests, the course regression
# and the installed-package consumer.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-dependencies.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build -j "$(nproc)"
ctest --test-dir build --output-on-failure -j "$(nproc)" "$@"
