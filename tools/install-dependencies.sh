#!/usr/bin/env bash
# Installs the Debian 12 packages prism builds with, if any is missing. Needs root (or sudo).
# --with-embree adds Embree 3 (the benchmarks' comparison); --with-chart adds what
# tools/chart.sh needs to turn its SVG into a PNG (rsvg-convert and a font); --with-browser adds
# Debian's Chromium, in which the test report/opens_in_chromium loads prism-suite's HTML report
# (skipped without it); --with-sanitizers adds clang 14 and its sanitizer runtimes, which build
# tools/sanitize.sh's instrumented tests; --with-fuzzers
# adds clang, its runtimes and zlib's headers for the libFuzzer harnesses (tools/fuzz.sh).
set -euo pipefail
# Ninja schedules every build of the scripts (tools/configure-build.sh says why).
packages=(build-essential cmake ninja-build pkg-config libglm-dev libtinyexr-dev libstb-dev nlohmann-json3-dev
          libpugixml-dev libtbb-dev doctest-dev libbenchmark-dev)
for option in "$@"; do
  case "$option" in
    --with-embree) packages+=(libembree-dev) ;;
    --with-chart) packages+=(librsvg2-bin fonts-dejavu-core) ;;
    --with-browser) packages+=(chromium) ;;
    --with-sanitizers) packages+=(clang-14 libclang-rt-14-dev) ;;
    --with-fuzzers) packages+=(clang-14 libclang-rt-14-dev zlib1g-dev) ;;
    *) echo "install-dependencies.sh: unknown option $option (expected --with-embree, --with-chart, --with-browser, --with-sanitizers or --with-fuzzers)" >&2; exit 2 ;;
  esac
done
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  sudo=""; [[ $(id -u) -ne 0 ]] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
