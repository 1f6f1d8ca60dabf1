#!/usr/bin/env bash
# One scene rendered by several `prism` binaries, paired: every round runs each binary once, the
# order rotated from round to round, so that a shared machine's load and drift fall on all of
# them alike. Each binary's time is taken over the first binary's of the same round; the medians
# and ranges of those ratios are what bench/RESULTS.md records ("Whole renders", "Path tracer").
# Every render's images are compared with the first binary's of its round (bench/same_pixels.py:
# the same bytes, or the same pixels decoded): a binary that wrote other pixels is reported,
# since a ratio between different images means little.
#
#   bash bench/paired.sh ROUNDS SCENE [--cpu N] LABEL=PRISM [LABEL=PRISM]... [-- PRISM_OPTIONS...]
#
#   bash bench/paired.sh 9 ../shared/ceng795/hw4/2017S_goksuguvendiren/inputs/5/glass_plates_point.xml \
#       fb59e22=FB59E22/build/examples/prism main=build/examples/prism -- --threads 2 --scale 0.5
#
# Prints per binary: the median user and wall times (s), then user and wall time over the first
# binary's, as median (min-max) of the rounds, and "same images" or how many rounds differed.
#
# The machine's vCPUs are probed around every render: a fixed loop timed on each vCPU the render
# may use. On the 2-vCPU VMs a vCPU runs the same loop 2.2 times slower for seconds to minutes at
# a time, each vCPU on its own (docs/benchmarks.md, "The machine"), so a render is "quiet" when
# every probe before and after it ran within 1.25 of the fastest probe of the run on any vCPU
# (the vCPUs are alike: measured against its own fastest, a vCPU slow for the whole run would
# count as quiet). The last line gives each binary's ratios over the rounds in which both it
# and the first binary rendered quietly. --cpu N pins every render (and the probes) to vCPU N,
# for one-thread runs.
set -euo pipefail

if [[ $# -lt 3 ]]; then
  sed -n '2,24p' "$0" >&2
  exit 2
fi
rounds=$1 scene=$2
shift 2
cpus=$(seq 0 $(($(nproc) - 1)))
pin=()
if [[ ${1:-} == --cpu ]]; then
  [[ ${2:-} =~ ^[0-9]+$ ]] || { echo "paired.sh: --cpu takes a vCPU number" >&2; exit 2; }
  cpus=$2 pin=(taskset -c "$2")
  shift 2
fi
labels=() binaries=()
while [[ $# -gt 0 && $1 != -- ]]; do
  [[ $1 == *=* ]] || { echo "paired.sh: expected LABEL=PRISM, got $1" >&2; exit 2; }
  labels+=("${1%%=*}") binaries+=("${1#*=}")
  shift
done
[[ $# -gt 0 ]] && shift
options=("$@")
for binary in "${binaries[@]}"; do
  [[ -x $binary ]] || { echo "paired.sh: $binary is not an executable" >&2; exit 2; }
done
[[ -f $scene ]] || { echo "paired.sh: no scene file $scene" >&2; exit 2; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The probe: about 0.1 s of dependent multiply-adds on a quiet vCPU of these VMs, whose time
# depends on nothing but the core's speed (no memory, no system calls).
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
probe() {  # probe ROUND K WHEN: each vCPU's time for the loop
  ((probing)) || return 0
  for cpu in $cpus; do
    echo "$1 $2 $3 $cpu $(taskset -c "$cpu" "$work/probe")" >> "$work/probes"
  done
}
touch "$work/probes"
count=${#binaries[@]}
for ((round = 0; round < rounds; ++round)); do
  for ((j = 0; j < count; ++j)); do
    k=$(((j + round) % count))
    out=$work/out_$k
    rm -rf "$out"
    probe "$round" "$k" before
    if ! /usr/bin/time -o "$work/time" -f '%e %U' "${pin[@]}" "${binaries[$k]}" "$scene" "${options[@]}" --output-dir "$out" \
      > "$work/log" 2>&1; then
      echo "paired.sh: ${labels[$k]} failed on $scene:" >&2
      tail -5 "$work/log" >&2
      exit 1
    fi
    probe "$round" "$k" after
    read -r wall user < "$work/time"
    echo "$round $k $wall $user" >> "$work/times"
  done
  for ((k = 1; k < count; ++k)); do
    same=1
    for image in "$work/out_0"/*; do
      [[ -f $work/out_$k/$(basename "$image") ]] &&
        python3 "$(dirname "$0")/same_pixels.py" "$image" "$work/out_$k/$(basename "$image")" || same=0
    done
    [[ $(ls "$work/out_0" | wc -l) == $(ls "$work/out_$k" | wc -l) ]] || same=0
    echo "$round $k $same" >> "$work/same"
  done
done
touch "$work/same"
python3 - "$work/times" "$work/same" "$work/probes" "${labels[@]}" <<'EOF'
import statistics, sys
times, same, probes, labels = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
wall, user = {}, {}
for line in open(times):
    r, k, w, u = line.split()
    wall[(int(r), int(k))] = float(w)
    user[(int(r), int(k))] = float(u)
differing = {}
for line in open(same):
    r, k, s = line.split()
    if s == "0":
        differing[int(k)] = differing.get(int(k), 0) + 1
rounds = sorted({r for r, _ in wall})
def spread(values):
    if not values:
        return "n/a (times under the timer's 10 ms)"
    return f"{statistics.median(values):.3f} ({min(values):.3f}-{max(values):.3f})"
for k, label in enumerate(labels):
    u = [user[(r, k)] for r in rounds]
    w = [wall[(r, k)] for r in rounds]
    line = f"{label:>14}  user {statistics.median(u):7.2f} s  wall {statistics.median(w):7.2f} s"
    if k > 0:
        line += f"  /{labels[0]}: user {spread([user[(r, k)] / user[(r, 0)] for r in rounds if user[(r, 0)] > 0])}"
        line += f", wall {spread([wall[(r, k)] / wall[(r, 0)] for r in rounds if wall[(r, 0)] > 0])}"
        line += "  same images" if k not in differing else f"  OTHER IMAGES in {differing[k]} of {len(rounds)} rounds"
    print(line)
# The probes: a render is quiet when every probe around it ran within 1.25 of the fastest probe
# on any vCPU (full speed).
probe_times = {}
for line in open(probes):
    r, k, _, cpu, t = line.split()
    probe_times.setdefault((int(r), int(k)), []).append((cpu, float(t)))
if probe_times:
    fastest = {}
    for values in probe_times.values():
        for cpu, t in values:
            fastest[cpu] = min(fastest.get(cpu, t), t)
    full_speed = min(fastest.values())
    quiet = {key for key, values in probe_times.items() if all(t <= 1.25 * full_speed for _, t in values)}
    slowest = max(t for values in probe_times.values() for _, t in values) / full_speed
    summary = ", ".join(f"vCPU {cpu} {fastest[cpu]:.3f} s" for cpu in sorted(fastest))
    print(f"probes: fastest {summary}; the slowest probe {slowest:.2f} times the fastest; "
          f"{len(quiet)} of {len(probe_times)} renders quiet")
    for k, label in enumerate(labels[1:], 1):
        both = [r for r in rounds if (r, 0) in quiet and (r, k) in quiet]
        if not both:
            print(f"{label:>14}  no round in which both it and {labels[0]} rendered quietly")
            continue
        print(f"{label:>14}  quiet rounds {len(both)} of {len(rounds)}: /{labels[0]}: user "
              f"{spread([user[(r, k)] / user[(r, 0)] for r in both if user[(r, 0)] > 0])}"
              f", wall {spread([wall[(r, k)] / wall[(r, 0)] for r in both if wall[(r, 0)] > 0])}")
EOF
