#!/usr/bin/env bash
# prism-suite --report refuses what it cannot write, before rendering anything: one line naming
# the folder and why, exit status 2, and no table printed.
#   bash tests/check_report_errors.sh PRISM_SUITE SCENES_FOLDER WORK_FOLDER
set -euo pipefail
suite=$1 scenes=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
touch "$work/a-file"
fail() { echo "FAIL: $*" >&2; exit 1; }

# expect STATUS PATTERN ARGS...: the run exits with STATUS, prints PATTERN on stderr in one line
# and renders nothing.
expect() {
  local want=$1 pattern=$2
  shift 2
  local status=0
  "$suite" "$scenes" --topics lights "$@" > "$work/out.txt" 2> "$work/err.txt" || status=$?
  echo "prism-suite ... $*: exit $status: $(head -n 1 "$work/err.txt")"
  [[ $status == "$want" ]] || fail "exit status $status, expected $want"
  grep -q -- "$pattern" "$work/err.txt" || fail "stderr lacks '$pattern': $(cat "$work/err.txt")"
  ! grep -q 'status' "$work/out.txt" || fail "it rendered before refusing"
}

expect 2 "--report $work/a-file/report: cannot create the folder" --report "$work/a-file/report"
expect 2 "--report $work/a-file: cannot create the folder" --report "$work/a-file"
expect 2 "--report needs a folder" --report ""
expect 2 "--report needs a value" --report
echo "every bad --report refused"
