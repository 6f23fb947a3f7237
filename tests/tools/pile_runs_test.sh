#!/usr/bin/env bash
# Piles as a user makes them (tools/stacks/pile.py) run through instants where many contacts meet:
# seed 2's pile of 100 spheres lets a sphere go from the floor at t = 0.24458 s, lifting and pressed
# by gravity at once; its pair was checked 1.1 million times at that instant and the run stopped
# with "the clock stopped advancing" (exit 2). Every run here must end normally (exit 0).
# Usage: pile_runs_test.sh PALPABLE PYTHON SOURCE_DIR
set -uo pipefail
palpable=$1
python=$2
source_dir=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
for spec in "100 sphere 0.26 --seed 2" "50 sphere 0.3 --seed 7" "30 hull 0.3 --seed 3"; do
  scene="$work/pile.json"
  # shellcheck disable=SC2086
  "$python" "$source_dir/tools/stacks/pile.py" $spec >"$scene" || { echo "FAIL pile.py $spec"; fail=1; continue; }
  if "$palpable" run "$scene" >/dev/null 2>"$work/err"; then
    echo "ok   pile $spec"
  else
    echo "FAIL pile $spec (exit $?): $(tail -c 400 "$work/err")"
    fail=1
  fi
done
exit $fail
