#!/usr/bin/env bash
# tools/stacks/restart.py as a user runs it: a scene restarted from a trace sample starts exactly
# at that sample (every dynamic body's position, orientation, velocity and angular velocity in the
# restarted run's first sample equal the original's at T, to the last digit), runs, and bad input
# (no sample at T, a missing trace, a file that is not a trace, a body missing from the sample)
# exits 2 naming the file and leaves no output file behind.
# Usage: restart_test.sh PALPABLE PYTHON SOURCE_DIR
set -uo pipefail
palpable=$1
python=$2
source_dir=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
script="$source_dir/tools/stacks/restart.py"
scene="$source_dir/scenarios/balls_in_dish.json"
"$palpable" run "$scene" --set /end_time=0.2 --trace "$work/t.csv" >/dev/null || {
  echo "FAIL the original run"; exit 1; }
"$python" "$script" "$scene" "$work/t.csv" 0.1 -o "$work/r.json" || {
  echo "FAIL restart.py exited $?"; exit 1; }
"$palpable" run "$work/r.json" --set /end_time=0.01 --trace "$work/r.csv" >/dev/null || {
  echo "FAIL the restarted run"; exit 1; }
"$python" - "$work/t.csv" "$work/r.csv" <<'PY' || fail=1
import csv, sys
at = {r["body"]: r for r in csv.DictReader(open(sys.argv[1])) if abs(float(r["t"]) - 0.1) < 1e-9}
start = {r["body"]: r for r in csv.DictReader(open(sys.argv[2])) if float(r["t"]) == 0.0}
columns = ["x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz"]
moving = [b for b in at if any(float(at[b][c]) != 0.0 for c in ("vx", "vy", "vz"))]
bad = [(b, c) for b in at for c in columns if float(at[b][c]) != float(start[b][c])]
if len(at) < 6 or not moving or bad:
    print(f"FAIL restarted state: {len(at)} bodies, {len(moving)} moving, mismatches {bad[:4]}")
    sys.exit(1)
PY
expect_bad() {  # expect_bad NAME WORD ARGS... : exit 2, stderr naming WORD, no output file
  local name=$1 word=$2; shift 2
  "$python" "$script" "$@" -o "$work/bad.json" 2>"$work/err.txt"
  local rc=$?
  if [ "$rc" -ne 2 ] || ! grep -q -- "$word" "$work/err.txt" || [ -e "$work/bad.json" ]; then
    echo "FAIL $name: rc $rc, stderr: $(cat "$work/err.txt")"; fail=1
  fi
}
expect_bad "no sample at T" "t.csv" "$scene" "$work/t.csv" 0.123
expect_bad "missing trace" "nope.csv" "$scene" "$work/nope.csv" 0.1
printf 'time,name\n0.1,ball0\n' > "$work/other.csv"
expect_bad "not a trace" "other.csv: not a palpable trace: no column 't'" "$scene" "$work/other.csv" 0.1
grep -v ",ball1," "$work/t.csv" > "$work/short.csv"
expect_bad "body missing" "short.csv" "$scene" "$work/short.csv" 0.1
exit $fail
