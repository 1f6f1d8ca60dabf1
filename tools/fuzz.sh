#!/usr/bin/env bash
# Fuzzes one of prism's readers with libFuzzer (clang, AddressSanitizer + UndefinedBehaviorSanitizer).
#   bash tools/fuzz.sh TARGET SECONDS [extra libFuzzer flags]
#   bash tools/fuzz.sh build          (builds the four harnesses at once, on every core, and exits)
# TARGET: xml | json (scene loaders, to the scene description), ply (PLY reader), image (stb and
# tinyexr behind decode_image). Builds what it needs in build-fuzz/, seeds the corpus
# build-fuzz/corpus/TARGET from ../shared (and the repository's own scenes) the first time, runs
# for SECONDS and prints libFuzzer's summary. Exit status: 0 when nothing was found, non-zero on a
# finding (the input that triggered it is left in build-fuzz/findings/TARGET/).
set -euo pipefail
cd "$(dirname "$0")/.."

if [[ $# -lt 2 && ${1:-} != build ]]; then
  echo "usage: bash tools/fuzz.sh xml|json|ply|image SECONDS [libFuzzer flags] | bash tools/fuzz.sh build" >&2
  exit 2
fi
target=$1 seconds=${2:-0} max_len=65536
shift $(($# < 2 ? $# : 2))
case "$target" in
  build) binary="fuzz_scene_xml fuzz_scene_json fuzz_ply fuzz_image" ;;
  xml) binary=fuzz_scene_xml patterns=("*.xml") ;;
  json) binary=fuzz_scene_json patterns=("*.json") ;;
  ply) binary=fuzz_ply patterns=("*.ply") ;;
  image) binary=fuzz_image max_len=16384 patterns=("*.png" "*.jpg" "*.jpeg" "*.hdr" "*.exr" "*.bmp" "*.tga" "*.ppm") ;;
  *) echo "fuzz.sh: unknown target '$target' (xml, json, ply or image)" >&2; exit 2 ;;
esac
if [[ $target != build ]] && { ! [[ "$seconds" =~ ^[0-9]+$ ]] || [[ "$seconds" -lt 1 ]]; }; then
  echo "fuzz.sh: SECONDS must be a positive whole number" >&2
  exit 2
fi

# clang 14, libFuzzer's runtime and zlib's headers, where missing.
bash tools/install-dependencies.sh --with-fuzzers >&2

build=build-fuzz
if [[ ! -f $build/CMakeCache.txt ]]; then
  cmake -S . -B $build -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14 \
        -DPRISM_BUILD_FUZZERS=ON -DPRISM_BUILD_EXAMPLES=OFF -DPRISM_BUILD_TESTS=OFF >/dev/null
fi
# shellcheck disable=SC2086 # "build" names the four harnesses
cmake --build $build --target $binary -j "$(nproc)" >/dev/null
[[ $target == build ]] && exit 0

# The seed corpus: the course's files of the target's kind, up to 64 KiB each (libFuzzer reads
# only the first -max_len bytes of a larger one: 64 KiB, 16 KiB for images, whose decoding under
# the sanitizers is slow), copied once; the corpus then grows by itself.
corpus=$build/corpus/$target
findings=$build/findings/$target
mkdir -p "$corpus" "$findings"
if [[ -z "$(ls -A "$corpus")" ]]; then
  names=()
  for pattern in "${patterns[@]}"; do names+=(-iname "$pattern" -o); done
  unset 'names[${#names[@]}-1]'
  for folder in ../shared scenes tests/data; do
    [[ -d $folder ]] || continue
    find "$folder" -type f \( "${names[@]}" \) -size -65k -print0 |
      while IFS= read -r -d '' file; do cp "$file" "$corpus/$(sha1sum "$file" | cut -c1-40)"; done
  done
  [[ -d ../shared ]] || echo "fuzz.sh: ../shared is missing: the corpus starts from the repository's files only" >&2
fi

# -rss_limit_mb: a reader that needs more than 2 GiB for an input of at most 64 KiB is a finding.
set +e
"$build/fuzz/$binary" "$corpus" -max_total_time="$seconds" -max_len="$max_len" -rss_limit_mb=2048 -timeout=25 \
  -artifact_prefix="$findings/" -print_final_stats=1 "$@" 2>"$build/fuzz-$target.log"
status=$?
set -e
grep -E "^(#[0-9]+ +DONE|Done [0-9]+ runs|stat::number_of_executed_units|stat::peak_rss_mb|==[0-9]+==ERROR|SUMMARY|artifact_prefix|Test unit written)" \
  "$build/fuzz-$target.log" || true
if [[ $status -ne 0 ]]; then
  echo "fuzz.sh: $target: a finding (libFuzzer exit $status); the full log is $build/fuzz-$target.log" >&2
  tail -n 40 "$build/fuzz-$target.log" >&2
  exit 1
fi
echo "fuzz.sh: $target: no finding"
