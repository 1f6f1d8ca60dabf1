#!/usr/bin/env bash
# The benchmark charts in one command: installs what is missing (the build's Debian packages,
# librsvg2-bin and a font for the PNG), builds the chart's program (Release) in build-chart/,
# renders, and writes the chart as SVG, PNG (converted from the SVG, so both show one chart), TSV
# and a marked section of bench/RESULTS.md.
#   bash tools/chart.sh [ARGS]           speed against accuracy of intersectors, precision and ray
#                                        offsets (tracker issue 3): bench/chart/speed_accuracy.*
#   bash tools/chart.sh sampling [ARGS]  error against time of the path tracer's sampling
#                                        strategies (issue 13): bench/chart/sampling.*, and of
#                                        the samplers (issue 32): bench/chart/samplers.*
# ARGS go to the program: `bash tools/chart.sh --scale 0.25 --runs 3` is a quick look; `--help`
# lists them.
set -euo pipefail
cd "$(dirname "$0")/.."
chart=accuracy
if [[ "${1:-}" == "sampling" ]]; then
  chart=sampling
  shift
fi
if [[ "$chart" == "sampling" ]]; then
  program=prism_sampling_chart stem=sampling sources=bench/sampling_chart.cpp
else
  program=prism_accuracy_chart stem=speed_accuracy sources=bench/accuracy_chart.cpp
fi
for argument in "$@"; do
  if [[ "$argument" == "--help" || "$argument" == "-h" ]] && [[ -x build-chart/bench/$program ]]; then
    exec "build-chart/bench/$program" --help
  fi
done
bash tools/install-dependencies.sh --with-chart
cmake -S . -B build-chart -DCMAKE_BUILD_TYPE=Release -DPRISM_BUILD_BENCHMARKS=ON -DPRISM_BUILD_TESTS=OFF \
      -DPRISM_BUILD_EXAMPLES=OFF > /dev/null
cmake --build build-chart -j "$(nproc)" --target "$program"
# The revision the numbers belong to, and whether the code the program compiles had local edits.
revision=$(git rev-parse --short HEAD 2>/dev/null || echo "not a git checkout")
edited=$(git status --porcelain -- include bench/*.hpp "$sources" 2>/dev/null | wc -l || true)
if [[ "$edited" != "0" ]]; then revision+=" + $edited uncommitted file(s) under include/ or bench/"; fi
command="bash tools/chart.sh"
[[ "$chart" == "sampling" ]] && command+=" sampling"
"build-chart/bench/$program" --output-dir bench/chart --results bench/RESULTS.md \
    --command "$command${*:+ $*}" --revision "$revision" "$@"
rsvg-convert --format png --background-color white --output "bench/chart/$stem.png" "bench/chart/$stem.svg"
if [[ "$chart" == "sampling" ]]; then
  rsvg-convert --format png --background-color white --output bench/chart/samplers.png bench/chart/samplers.svg
fi
echo "wrote bench/chart/$stem.svg, bench/chart/$stem.png and the $chart chart's section of bench/RESULTS.md"
