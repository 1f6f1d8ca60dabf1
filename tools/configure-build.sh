#!/usr/bin/env bash
# Configures `build`, the Release folder that tools/render-default.sh and tools/test.sh share,
# with the options given. A new folder is made for Ninja: Make starts a target's objects only once
# the libraries it links are built, so the unit tests' three long groups started last and the
# last of them compiled alone on one core (74 s of CI's Release build at ce6365f); Ninja starts
# them first (they come first in the build files). A folder made before keeps its generator, which
# CMake cannot change in place.
set -euo pipefail
cd "$(dirname "$0")/.."
generator=()
[[ -f build/CMakeCache.txt ]] || generator=(-G Ninja)
cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "$@" > /dev/null
