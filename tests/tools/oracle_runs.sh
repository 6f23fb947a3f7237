# Sourced by the oracle tests (rattleback_oracle_test.sh, euler_disk_oracle_test.sh), which set
# palpable, work and fail. run_traced NAME SCENE END [SET ...]: palpable runs SCENE to END at
# integration tolerance 1e-11 with the --set values SET, writing $work/NAME.csv and
# $work/NAME.events.csv; if it fails, prints why, sets fail=1 and returns 1.
run_traced() {
  local name=$1 scene=$2 end=$3 code=0
  shift 3
  local sets=(--set /settings/integration_tolerance=1e-11 --set "/end_time=$end")
  for s in "$@"; do sets+=(--set "$s"); done
  "$palpable" run "$scene" "${sets[@]}" --trace "$work/$name.csv" \
    --events "$work/$name.events.csv" >/dev/null 2>"$work/err" || code=$?
  if [ "$code" -ne 0 ]; then
    echo "FAIL $name: palpable exit $code: $(tail -c 400 "$work/err")"
    fail=1
    return 1
  fi
}
