#!/usr/bin/env bash
# The README's first command: install what is missing, build the renderer in Release, and render
# the default scene into out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-dependencies.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPRISM_BUILD_TESTS=OFF > /dev/null
cmake --build build --target prism-render -j "$(nproc)"
./build/examples/prism scenes/default.xml --output-dir out
