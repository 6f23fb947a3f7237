#!/usr/bin/env bash
# scenarios/eulers_disk.json with rolling resistance 1e-4 m, sliding at its friction cone from
# 5.0761 s, against tools/euler-disk-oracle --slide (an independent plain-Python RK4 of the
# cylinder with its rim sliding under Coulomb friction, regularised in the slip's direction at
# eps 1e-5 m/s), from the run's first slip event to 5.6 s: Omega and c within 1 % of their size
# at every sample (measured: c within 0.5 %, 3.4e-6 m of 6.6e-4; Omega within 0.24 %, 0.16 of
# 67 rad/s). The check must be able to fail: the oracle run with mu 1 % off (0.303) has to fail
# it (measured: c 2 % off, 1.4e-5 m).
# Usage: euler_disk_sliding_oracle_test.sh PALPABLE PYTHON SOURCE_DIR
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
slide() {  # extra oracle options; the oracle's exit code
  "$python" "$oracle" "$work/sliding.csv" --events "$work/sliding.events.csv" --slide \
    --end 5.6 --eps 1e-5 --dt 2.2e-6 --check 0.01 "$@" >"$work/out" 2>&1
}
if run_traced sliding "$source_dir/scenarios/eulers_disk.json" 5.6 \
    /materials/default/rolling_resistance=1e-4; then
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
exit $fail
