#!/usr/bin/env bash
# Whole-process wall time of two `prism` binaries on the course scenes, paired: every round runs
# each scene with both binaries back to back, in alternating order, so the load of a shared
# machine falls on both alike. Prints one line per scene: the median of each binary's times, the
# median of the per-round ratios new/old, and whether the two binaries wrote the same images
# (cmp, byte for byte). Used for bench/RESULTS.md ("Whole renders").
#
#   bash bench/whole_process.sh OLD_PRISM NEW_PRISM [--rounds N] [--threads T] [--shared DIR]
#                               [--topics hw1,hw2] [--extra PATH]... [--base BASE_PRISM]
#                               [-- NEW_PRISM_OPTIONS...]
#
# --base adds a third binary to every round (a branch's base, say), with its median time, the
# median of the per-round ratios new/base and whether new wrote the same pixels as it.
#
# Scenes: every distinct hw1/hw2 path of MANIFEST.tsv (default) and each --extra path (relative
# to the course folder). Scenes either binary refuses are listed as such and skipped.
#
# Each vCPU is probed before and after every render (a fixed loop, as bench/paired.sh does): on
# the 2-vCPU VMs a vCPU can run at less than half speed for seconds to minutes
# (docs/benchmarks.md, "The machine"). A round is quiet when every probe around its renders ran
# within 1.25 of the fastest probe so far on any vCPU (the vCPUs are alike: measured against its
# own fastest, a vCPU slow since the start would count as quiet); the last two columns are the
# number of quiet rounds and the median of new/old over them ("-" when none was).
set -euo pipefail

old=$1 new=$2
shift 2
rounds=3 threads=2 shared=../shared topics=hw1,hw2 base=
extras=()
new_options=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --rounds) rounds=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --shared) shared=$2; shift 2 ;;
    --topics) topics=$2; shift 2 ;;
    --extra) extras+=("$2"); shift 2 ;;
    --base) base=$2; shift 2 ;;
    --) shift; new_options=("$@"); break ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
course=$shared/ceng795
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

mapfile -t scenes < <(awk -F'\t' -v topics=",$topics," 'NR > 1 && index(topics, "," $1 ",") { print $4 }' \
                        "$course/MANIFEST.tsv" | sort -u)
scenes+=("${extras[@]}")

# The probe: about 0.1 s of dependent multiply-adds on a vCPU at full speed.
cat > "$work/probe.c" <<'PROBE'
#include <stdio.h>
#include <time.h>
int main(void) {
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    volatile unsigned long x = 0;
    for (unsigned long i = 0; i < 300000000UL; ++i) x += i * i;
    clock_gettime(CLOCK_MONOTONIC, &b);
    printf("%.4f\n", (double)(b.tv_sec - a.tv_sec) + (double)(b.tv_nsec - a.tv_nsec) * 1e-9);
    return 0;
}
PROBE
probing=0
if command -v cc > /dev/null && command -v taskset > /dev/null && cc -O1 -o "$work/probe" "$work/probe.c" 2> /dev/null; then
  probing=1
fi
fastest=
declare -A fastest_on  # each vCPU's own fastest, for the summary line
quiet=1
probe() {  # each vCPU's time for the loop; clears `quiet` when one ran slower than 1.25 of the fastest
  ((probing)) || return 0
  local cpu t
  for ((cpu = 0; cpu < $(nproc); ++cpu)); do
    t=$(taskset -c "$cpu" "$work/probe")
    if [[ -z $fastest ]] || (($(echo "$t < $fastest" | bc -l))); then fastest=$t; fi
    if [[ -z ${fastest_on[$cpu]:-} ]] || (($(echo "$t < ${fastest_on[$cpu]}" | bc -l))); then fastest_on[$cpu]=$t; fi
    (($(echo "$t > 1.25 * $fastest" | bc -l))) && quiet=0
  done
  return 0
}
for _ in 1 2 3 4 5; do probe; done  # the fastest, before the first round reads it

now() { date +%s.%N; }
run() {  # binary, output folder, scene, options...: prints seconds, or "refused"
  local binary=$1 out=$2 scene=$3
  shift 3
  rm -rf "$out" && mkdir -p "$out"
  local start end
  start=$(now)
  if "$binary" "$course/$scene" --output-dir "$out" --threads "$threads" --quiet "$@" >/dev/null 2>&1; then
    end=$(now)
    echo "$end - $start" | bc -l
  else
    echo refused
  fi
}
# Whether two image files hold the same pixels (bench/same_pixels.py: PNGs and EXRs are
# decoded, as the two binaries may compress the same pixels differently).
same_pixels() {
  [[ -f $2 ]] || return 1
  python3 "$(dirname "$0")/same_pixels.py" "$1" "$2"
}
median() { sort -g | awk '{ a[NR] = $1 } END { print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2 }'; }

if [[ -n $base ]]; then
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' scene old_s new_s new/old same_images base_s new/base same_as_base \
    quiet_rounds quiet_new/old
else
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' scene old_s new_s new/old same_images quiet_rounds quiet_new/old
fi
for scene in "${scenes[@]}"; do
  old_times=() new_times=() ratios=() base_times=() base_ratios=() refused= quiet_ratios=()
  for ((round = 0; round < rounds; ++round)); do
    t_base=0
    quiet=1
    probe
    if ((round % 2 == 0)); then
      t_old=$(run "$old" "$work/old" "$scene")
      probe
      [[ -n $base ]] && t_base=$(run "$base" "$work/base" "$scene") && probe
      t_new=$(run "$new" "$work/new" "$scene" "${new_options[@]}")
    else
      t_new=$(run "$new" "$work/new" "$scene" "${new_options[@]}")
      probe
      [[ -n $base ]] && t_base=$(run "$base" "$work/base" "$scene") && probe
      t_old=$(run "$old" "$work/old" "$scene")
    fi
    probe
    if [[ $t_old == refused || $t_new == refused || $t_base == refused ]]; then refused=yes; break; fi
    old_times+=("$t_old") new_times+=("$t_new") ratios+=("$(echo "$t_new / $t_old" | bc -l)")
    ((quiet && probing)) && quiet_ratios+=("$(echo "$t_new / $t_old" | bc -l)")
    if [[ -n $base ]]; then base_times+=("$t_base") base_ratios+=("$(echo "$t_new / $t_base" | bc -l)"); fi
  done
  if [[ -n $refused ]]; then
    printf '%s\trefused\n' "$scene"
    continue
  fi
  same=yes
  for image in "$work"/old/*; do
    same_pixels "$image" "$work/new/$(basename "$image")" || same=no
  done
  printf '%s\t%.3f\t%.3f\t%.3f\t%s' "$scene" \
    "$(printf '%s\n' "${old_times[@]}" | median)" "$(printf '%s\n' "${new_times[@]}" | median)" \
    "$(printf '%s\n' "${ratios[@]}" | median)" "$same"
  if [[ -n $base ]]; then
    same_base=yes
    for image in "$work"/base/*; do
      same_pixels "$image" "$work/new/$(basename "$image")" || same_base=no
    done
    printf '\t%.3f\t%.3f\t%s' "$(printf '%s\n' "${base_times[@]}" | median)" \
      "$(printf '%s\n' "${base_ratios[@]}" | median)" "$same_base"
  fi
  if ((${#quiet_ratios[@]})); then
    printf '\t%d\t%.3f\n' "${#quiet_ratios[@]}" "$(printf '%s\n' "${quiet_ratios[@]}" | median)"
  else
    printf '\t0\t-\n'
  fi
done
if ((probing)); then
  summary=
  for ((cpu = 0; cpu < $(nproc); ++cpu)); do summary+=" vCPU $cpu ${fastest_on[$cpu]} s"; done
  echo "probes: the fastest of each:$summary (quiet: within 1.25 of the fastest)" >&2
fi
