#!/usr/bin/env bash
# A pile through a storm of mode changes that ended nowhere (tools/stacks/pile.py; 35 s of CPU).
# 100 hulls, seed 2, at 0.7616 s: a hull tipping over its floor edge, the end of that edge
# touching a resting hull at the floor, had the floor contacts of the two hulls stop slipping in
# turn every 7e-10 s - 43,640 times in 3.4e-5 s, the run going no further in 120 s of CPU. An
# island whose motions keep ending within 1e-3 of the progress floor of their start now lets go
# of the contacts whose events end them (scheduler/simulation_hold.cpp, island_event). The pile
# must reach 0.77 s, and no pair may change modes 1,000 times within 1e-5 s (the most now: 105).
# Usage: pile_storms_test.sh PALPABLE PYTHON SOURCE_DIR
set -uo pipefail
palpable=$1
python=$2
source_dir=$3
# shellcheck source=tests/tools/harness.sh
. "$(dirname "$0")/harness.sh"
"$python" "$source_dir/tools/stacks/pile.py" 100 hull 0.77 --seed 2 >pile.json || exit 1
# The CPU budget only keeps a storm from running for ever (the run takes about 35 s of CPU).
"$palpable" run pile.json --events events.csv --cpu-limit 400 >/dev/null 2>err
status=$?
check "100 hulls, seed 2, reach 0.77 s (exit $status)" '[ "$status" -eq 0 ]'
# The kinds an island's mode changes report (Simulation's island events).
most=$("$python" "$source_dir/tests/tools/pair_event_peak.py" events.csv 1e-5 \
  stick,slip,spin_stop,roll_stop,lift_off,tip,landing)
check "no pair changes modes 1,000 times within 1e-5 s (the most: $most)" \
  '[ -n "$most" ] && [ "$most" -lt 1000 ]'
exit $fail
