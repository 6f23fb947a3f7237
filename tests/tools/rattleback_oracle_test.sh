#!/usr/bin/env bash
# scenarios/rattleback.json under the persistent model against tools/rattleback-oracle, an
# independent integration of the ellipsoid rolling without slip (plain Python RK4). With friction
# enough never to slip (mu 10), spun both ways and pitched: the angular velocity within 1e-5 rad/s
# of the oracle's (measured 5e-7, 6e-9 and 4e-8 rad/s at the run's integration tolerance 1e-11)
# and the spin reversing at the same sample (4.01 s spun at -5; never spun at +5). With the
# scene's mu 0.5 (spun at -5): 4e-7 rad/s until the rolling motion first needs more than mu N
# (2.1029 s), where the first slip event must be, within two oracle steps.
# scenarios/rattleback_kane_levinson.json (Kane & Levinson's body and start, centre of mass 1 cm
# below the centre, rolling from its first instant), spun the sense it reverses in, to 4 s: the
# spin changing sign at the same samples (2.77, 2.79, 2.81 s), within 1e-5 rad/s from t = 0.
# Usage: rattleback_oracle_test.sh PALPABLE PYTHON SOURCE_DIR
set -uo pipefail
palpable=$1
python=$2
source_dir=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
# shellcheck source=oracle_runs.sh
source "$(dirname "$0")/oracle_runs.sh"
check() {  # scene, name, end, oracle options, then palpable --set values
  local scene=$source_dir/scenarios/$1 name=$2 end=$3 oracle="$4 --scene $source_dir/scenarios/$1"
  shift 4
  run_traced "$name" "$scene" "$end" "$@" || return
  # shellcheck disable=SC2086
  if "$python" "$source_dir/tools/rattleback-oracle" "$work/$name.csv" --end "$end" $oracle \
      --check 1e-5; then
    echo "ok   $name"
  else
    echo "FAIL $name"
    fail=1
  fi
}
check rattleback.json spin_minus5_no_slip 5 "--mu 10" /parameters/spin=-5 /parameters/mu=10
check rattleback.json spin_plus5_no_slip 4 "--mu 10" /parameters/spin=5 /parameters/mu=10
check rattleback.json pitch_only_no_slip 4 "--mu 10" /parameters/spin=0 /parameters/mu=10
check rattleback.json spin_minus5_mu05 2.5 "--mu 0.5 --events $work/spin_minus5_mu05.events.csv" \
  /parameters/spin=-5
check rattleback_kane_levinson.json kane_levinson 4 "--mu 10 --from 0"
exit $fail
