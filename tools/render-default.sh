#!/usr/bin/env bash
# The README's first command: install what is missing, build the renderer in Release, and render
# the default scene into out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-dependencies.sh
# Sets what it needs (the examples) and leaves the tests' option as it finds it: the build
# folder is shared with tools/test.sh, which must never inherit the tests turned off from here.
bash tools/configure-build.sh -DPRISM_BUILD_EXAMPLES=ON
cmake --build build --target prism-render -j "$(nproc)"
./build/examples/prism scenes/default.xml --output-dir out
