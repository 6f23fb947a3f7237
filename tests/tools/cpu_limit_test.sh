#!/usr/bin/env bash
# palpable run --cpu-limit as a user meets it: a run stopped at its CPU budget exits 4, and its
# trace and events are the beginning of the whole run's, byte for byte (the run stops between two
# events, as the same run would pass that instant); its summary says where it stopped, and a
# closed form's figures, which are of the whole run, are withheld with the reason. A budget it
# does not reach changes nothing (exit 0, the same files). A budget that is not a number of
# seconds >= 0 is bad input: exit 2, the option named, no file written.
# (A budget of 0 stops the run at its first check, after 64 events: the same stop on any machine.)
# Usage: cpu_limit_test.sh PALPABLE SCENARIOS_DIR
set -uo pipefail
palpable=$1
scenes=$2
. "$(dirname "$0")/harness.sh"  # work (the current directory), fail, check
scene="$scenes/balls_in_dish.json"
"$palpable" run "$scene" --trace whole.csv --events whole.ev.csv >/dev/null 2>&1
check "the whole run exits 0" "[[ $? -eq 0 ]]"
"$palpable" run "$scene" --cpu-limit 0 --trace part.csv --events part.ev.csv \
    --summary-json part.json >summary.txt 2>&1
check "a run stopped at its budget exits 4" "[[ $? -eq 4 ]]"
prefix() {  # is file $1 the beginning of file $2, and shorter?
  local n
  n=$(stat -c %s "$1")
  [[ $n -gt 0 && $n -lt $(stat -c %s "$2") ]] && cmp -s -n "$n" "$1" "$2"
}
check "its trace is the beginning of the whole run's" "prefix part.csv whole.csv"
check "its events are the beginning of the whole run's" "prefix part.ev.csv whole.ev.csv"
check "its summary says it stopped at the CPU limit" \
    "grep -q 'stopped at the CPU limit (0 s)' summary.txt"
check "its JSON summary says where" "python3 - part.json <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
ok = s['stopped'] == {'reason': 'cpu_limit', 'cpu_limit_s': 0.0, 'end_time_s': 7.8}
ok = ok and 0.0 < s['virtual_time_s'] < 7.8 and s['events'] == 64
sys.exit(0 if ok else 1)
PY"
"$palpable" run "$scenes/block_on_ramp_decelerating.json" --cpu-limit 0 \
    --summary-json ref.json >/dev/null 2>&1
check "with a closed form, it exits 4 too" "[[ $? -eq 4 ]]"
check "... and withholds the closed form's figures, saying why" \
    "grep -q 'stopped at its CPU limit' ref.json"
"$palpable" run "$scene" --cpu-limit 1e9 --trace far.csv --events far.ev.csv >/dev/null 2>&1
check "a budget not reached: exit 0" "[[ $? -eq 0 ]]"
check "... and the same trace and events" "cmp -s far.csv whole.csv && cmp -s far.ev.csv whole.ev.csv"
for bad in -1 nan inf abc; do
  "$palpable" run "$scene" --cpu-limit "$bad" --trace bad.csv >/dev/null 2>err.txt
  rc=$?
  check "--cpu-limit $bad: exit 2, the option named, no file" \
      "[[ $rc -eq 2 ]] && grep -q -- '--cpu-limit' err.txt && [[ ! -e bad.csv ]]"
done
exit $fail
