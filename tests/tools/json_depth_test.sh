#!/usr/bin/env bash
# JSON nested 100,000 deep (a 200 KB document) crashed run and impact with a stack overflow
# (issue 20). Every JSON reader refuses documents nested deeper than 256 levels while parsing:
# exit 2, naming the file (or the option), no crash.
# Usage: json_depth_test.sh PALPABLE SCENARIOS_DIR
set -uo pipefail
palpable=$1
scenes=$2
. "$(dirname "$0")/harness.sh"  # work (the current directory), fail, check
nest() {  # N: an array nested N deep
  head -c "$1" /dev/zero | tr '\0' '['
  head -c "$1" /dev/zero | tr '\0' ']'
}

nest 100000 > deep.json
"$palpable" run deep.json >/dev/null 2>err.txt
code=$?
check "run of a 100,000-deep array: exit 2 (got $code)" "[[ $code -eq 2 ]]"
check "... naming the file and the limit" \
    "grep -q 'deep.json.*nested deeper than 256 levels' err.txt"

# The same depth inside a valid scene's description (where the crash was).
python3 - "$scenes/coins.json" > deep_description.json <<'PY'
import json, sys
scene = json.load(open(sys.argv[1]))
scene["description"] = "@"
print(json.dumps(scene).replace('"@"', "[" * 100000 + "]" * 100000))
PY
"$palpable" run deep_description.json >/dev/null 2>err.txt
code=$?
check "run of a scene whose description is 100,000 deep: exit 2 (got $code)" "[[ $code -eq 2 ]]"
check "... naming the file and the limit" \
    "grep -q 'deep_description.json.*nested deeper than 256 levels' err.txt"

"$palpable" impact deep.json >/dev/null 2>err.txt
code=$?
check "impact of a 100,000-deep spec: exit 2 (got $code)" "[[ $code -eq 2 ]]"
check "... naming the file and the limit" \
    "grep -q 'deep.json.*nested deeper than 256 levels' err.txt"

# On the command line (an argument is at most 128 KiB: 60,000 levels).
"$palpable" run "$scenes/coins.json" --set "/description=$(nest 60000)" >/dev/null 2>err.txt
code=$?
check "--set with a 60,000-deep value: exit 2 (got $code)" "[[ $code -eq 2 ]]"
check "... naming the limit" "grep -q 'nested deeper than 256 levels' err.txt"

# 256 levels are still read (the limit is not off by one the wrong way).
nest 256 > at_limit.json
"$palpable" run at_limit.json >/dev/null 2>err.txt
check "an array 256 deep is parsed (then refused as a scene, not for its depth)" \
    "grep -q 'expected an object' err.txt"
nest 257 > past_limit.json
"$palpable" run past_limit.json >/dev/null 2>err.txt
check "... 257 deep is refused for its depth" "grep -q 'nested deeper than 256 levels' err.txt"

exit $fail
