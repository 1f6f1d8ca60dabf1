#!/usr/bin/env bash
# The speed-against-accuracy chart (tracker issue 3) in one command: installs what is missing
# (the build's Debian packages, librsvg2-bin and a font for the PNG), builds
# prism_accuracy_chart (Release) in build-chart/, renders every chart scene with every variant,
# and writes bench/chart/speed_accuracy.{svg,png,tsv,md} and the marked section of
# bench/RESULTS.md. Arguments go to the program: `bash tools/chart.sh --scale 0.25 --runs 3`
# is a quick look; `--help` lists them. The PNG is converted from the SVG, so both show one chart.
set -euo pipefail
cd "$(dirname "$0")/.."
for argument in "$@"; do
  if [[ "$argument" == "--help" || "$argument" == "-h" ]] && [[ -x build-chart/bench/prism_accuracy_chart ]]; then
    exec build-chart/bench/prism_accuracy_chart --help
  fi
done
bash tools/install-dependencies.sh --with-chart
cmake -S . -B build-chart -DCMAKE_BUILD_TYPE=Release -DPRISM_BUILD_BENCHMARKS=ON -DPRISM_BUILD_TESTS=OFF \
      -DPRISM_BUILD_EXAMPLES=OFF > /dev/null
cmake --build build-chart -j "$(nproc)" --target prism_accuracy_chart
# The revision the numbers belong to, and whether the code the program compiles had local edits.
revision=$(git rev-parse --short HEAD 2>/dev/null || echo "not a git checkout")
edited=$(git status --porcelain -- include bench/accuracy_chart.cpp 2>/dev/null | wc -l || true)
if [[ "$edited" != "0" ]]; then revision+=" + $edited uncommitted file(s) under include/ or bench/"; fi
build-chart/bench/prism_accuracy_chart --output-dir bench/chart --results bench/RESULTS.md \
    --command "bash tools/chart.sh${*:+ $*}" --revision "$revision" "$@"
rsvg-convert --format png --background-color white --output bench/chart/speed_accuracy.png \
    bench/chart/speed_accuracy.svg
echo "wrote bench/chart/speed_accuracy.svg, bench/chart/speed_accuracy.png and the chart section of bench/RESULTS.md"
