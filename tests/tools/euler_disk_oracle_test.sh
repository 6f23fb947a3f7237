#!/usr/bin/env bash
# scenarios/eulers_disk.json under the persistent model against tools/euler-disk-oracle, an
# independent integration of the cylinder rolling without slip on its rim (plain Python RK4).
# At integration tolerance 1e-11, the angular velocity within 5e-5 rad/s of the oracle's while
# the rolling needs no more than mu N (measured: the steady motion at 20 degrees over 2 s 5.5e-7;
# rolling resistance 1e-4 m, to 5.08 s, 4.6e-6; spinning resistance 1e-4 m, to 3.08 s, 1.2e-6;
# the oracle's own step error 5e-8), and the simulator's first slip event within two oracle steps
# of the instant the rolling first needs more than mu N (5.0761 s; 3.0798 s), none in the steady
# motion. (At the scene's own tolerance 1e-9 the three measure 6.4e-5, 5.1e-4 and 1.3e-4.)
# From the rolling-resistance run's first slip to 5.6 s, against tools/euler-disk-oracle --slide
# (the rim sliding under Coulomb friction regularised in the slip's direction at eps 1e-5 m/s):
# Omega and c within 1 % of their size at every sample (measured: c within 0.5 %, 3.4e-6 m of
# 6.6e-4; Omega within 0.24 %, 0.16 of 67 rad/s); that check must fail with the oracle's mu 1 %
# off (0.303: c 2 % off, 1.4e-5 m).
# A missing or malformed trace is bad input: exit 2, the file named.
# Usage: euler_disk_oracle_test.sh PALPABLE PYTHON SOURCE_DIR
set -uo pipefail
palpable=$1
python=$2
source_dir=$3
oracle=$source_dir/tools/euler-disk-oracle
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
# shellcheck source=oracle_runs.sh
source "$(dirname "$0")/oracle_runs.sh"
check() {  # name, end, then palpable --set values (the oracle reads them from the trace's .json)
  local name=$1 end=$2
  shift 2
  run_traced "$name" "$source_dir/scenarios/eulers_disk.json" "$end" "$@" || return
  if "$python" "$oracle" "$work/$name.csv" --end "$end" --events "$work/$name.events.csv" \
      --check 5e-5 >"$work/out"; then
    echo "ok   $name"
  else
    echo "FAIL $name"
    cat "$work/out"
    fail=1
  fi
}
check steady_20deg 2
check rolling_resistance 5.6 /materials/default/rolling_resistance=1e-4
check spinning_resistance 3.2 /materials/default/spinning_resistance=1e-4
slide() {  # extra oracle options; the oracle's exit code
  "$python" "$oracle" "$work/rolling_resistance.csv" --slide \
    --events "$work/rolling_resistance.events.csv" --end 5.6 --eps 1e-5 --dt 2.2e-6 \
    --check 0.01 "$@" >"$work/out" 2>&1
}
if [ -f "$work/rolling_resistance.csv" ]; then
  if slide; then
    echo "ok   sliding"
  else
    echo "FAIL sliding"
    cat "$work/out"
    fail=1
  fi
  slide --mu 0.303
  code=$?
  if [ "$code" -eq 1 ]; then
    echo "ok   sliding_mu_1_percent_off_fails"
  else
    echo "FAIL sliding_mu_1_percent_off_fails: exit $code"
    cat "$work/out"
    fail=1
  fi
fi
bad_input() {  # name, trace file
  "$python" "$oracle" "$2" >/dev/null 2>"$work/err"
  local code=$?
  if [ "$code" -eq 2 ] && grep -qF "$2" "$work/err"; then
    echo "ok   $1"
  else
    echo "FAIL $1: exit $code, $(cat "$work/err")"
    fail=1
  fi
}
bad_input missing_trace "$work/missing.csv"
bad_input events_as_trace "$work/steady_20deg.events.csv"
exit $fail
