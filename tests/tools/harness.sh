# Sourced by the command-line tests (tests/tools/*_test.sh): a work directory, made current and
# removed on exit; `fail`, the script's exit status; and `check`, which prints one line per
# promise and sets fail where it does not hold.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
fail=0
check() {  # description, condition (a command)
  if eval "$2"; then echo "ok   $1"; else echo "FAIL $1"; fail=1; fi
}
