#!/usr/bin/env bash
# What reading a large or hostile scene file costs: peak resident memory and wall time of whole
# `prism` runs, two binaries alternated round by round, on scene files generated here. Each run's
# answer is checked: the exit status and the line on stderr it must give (or none), so a binary
# that fails for another reason is reported, not timed. Used for bench/RESULTS.md ("Reading
# scene files").
#
#   bash bench/scene_memory.sh OLD_PRISM NEW_PRISM [--rounds N] [--work DIR]
#
# Files (written to --work, default a temporary folder; about 450 MB):
#   tags_16M.xml      16,777,216 empty elements <a/> (64 MB) under <Scene>
#   tags_16M.json     the same as 16,777,216 empty objects {} in one array (48 MB)
#   tags_limit.xml    2^22 - 1 empty elements: the most prism reads
#   spheres_1M.xml    a camera, a light and 1,000,000 spheres (87 MB)
#   vertices_256M.xml a sphere and 256 MiB of inline VertexData ("0 " 44 million times)
set -euo pipefail

old=$1 new=$2
shift 2
rounds=3 work=
while [[ $# -gt 0 ]]; do
  case $1 in
    --rounds) rounds=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
if [[ -z $work ]]; then
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
fi
mkdir -p "$work"

python3 - "$work" <<'EOF'
import os, sys
work = sys.argv[1]
head = ('<Scene><Cameras><Camera id="1"><Position>0 0 10</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>'
        '<NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>16 16</ImageResolution>'
        '<ImageName>a.png</ImageName></Camera></Cameras>'
        '<Lights><PointLight id="1"><Position>0 0 10</Position><Intensity>100 100 100</Intensity></PointLight></Lights>'
        '<Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>')
sphere = '<Sphere id="%d"><Material>1</Material><Center>1</Center><Radius>1</Radius></Sphere>'
def write(name, parts):
    path = os.path.join(work, name)
    if os.path.exists(path): return
    with open(path, 'w') as f:
        for part in parts: f.write(part)
n = 1 << 24
write('tags_16M.xml', ['<Scene>', '<a/>' * n, '</Scene>'])
write('tags_16M.json', ['{"Scene":{"a":[', '{},' * (n - 1), '{}]}}'])
write('tags_limit.xml', ['<Scene>', '<a/>' * ((1 << 22) - 1), '</Scene>'])
write('spheres_1M.xml', [head, '<VertexData>0 0 0</VertexData><Objects>',
                         ''.join(sphere % (i + 1) for i in range(1000000)), '</Objects></Scene>'])
numbers = (256 * 1024 * 1024 - 600) // 2
numbers -= numbers % 3
write('vertices_256M.xml', [head, '<VertexData>', '0 ' * numbers, '</VertexData><Objects>', sphere % 1,
                            '</Objects></Scene>'])
EOF

# file|old answer|new answer: what stderr must hold (a regex), or "" for a clean render (no
# message, exit status 0). The old binary (before the node limit) reads every file whole.
cases=(
  "tags_16M.xml|the scene has no camera|more than 4194304 elements and attributes"
  "tags_16M.json|the scene has no camera|more than 4194304 elements and attributes"
  "tags_limit.xml|the scene has no camera|the scene has no camera"
  "spheres_1M.xml||more than 4194304 elements and attributes"
  "vertices_256M.xml||"
)

run() {  # binary, file, pattern: prints "seconds peak_MB status" or fails on a wrong answer
  local binary=$1 file=$2 pattern=$3
  local out="$work/out" err="$work/err" times="$work/time"
  rm -rf "$out"
  local status=0
  /usr/bin/time -f "%e %M" -o "$times" "$binary" "$work/$file" --output-dir "$out" --quiet --threads 2 2> "$err" || status=$?
  if [[ -n $pattern ]] && ! grep -Eq "$pattern" "$err"; then
    echo "wrong answer from $binary on $file: $(head -c 300 "$err")" >&2
    exit 1
  fi
  if [[ -z $pattern ]] && [[ -s $err || $status != 0 ]]; then
    echo "$binary did not render $file (exit $status): $(head -c 300 "$err")" >&2
    exit 1
  fi
  # The last line: GNU time writes "Command exited with non-zero status N" above it.
  read -r seconds kilobytes < <(tail -n 1 "$times")
  echo "$seconds $((kilobytes / 1024)) $status"
}

median() { sort -n | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

printf 'file\told_s\told_MB\told_exit\tnew_s\tnew_MB\tnew_exit\n'
for case in "${cases[@]}"; do
  IFS='|' read -r file old_pattern new_pattern <<< "$case"
  old_s=() old_mb=() new_s=() new_mb=() old_exit= new_exit=
  for ((r = 0; r < rounds; ++r)); do
    # Alternating which binary goes first, so that the page cache and the machine's load fall on both.
    order=(old new)
    ((r % 2)) && order=(new old)
    for side in "${order[@]}"; do
      if [[ $side == old ]]; then
        result=$(run "$old" "$file" "$old_pattern")
        read -r s mb e <<< "$result"; old_s+=("$s"); old_mb+=("$mb"); old_exit=$e
      else
        result=$(run "$new" "$file" "$new_pattern")
        read -r s mb e <<< "$result"; new_s+=("$s"); new_mb+=("$mb"); new_exit=$e
      fi
    done
  done
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$file" \
    "$(printf '%s\n' "${old_s[@]}" | median)" "$(printf '%s\n' "${old_mb[@]}" | median)" "$old_exit" \
    "$(printf '%s\n' "${new_s[@]}" | median)" "$(printf '%s\n' "${new_mb[@]}" | median)" "$new_exit"
done
