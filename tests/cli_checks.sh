# Shared by the command-line test scripts (sourced, not run): `check` and `fails_with` count
# failures; `finish` reports them and sets the exit status.
failures=0
check() { # description, then a command that must succeed
  local what=$1; shift
  if "$@"; then echo "ok   $what"; else echo "FAIL $what"; failures=$((failures + 1)); fi
}
fails_with() { # description, expected message part, command that must fail with it
  local what=$1 part=$2; shift 2
  local out rc
  out=$("$@" 2>&1 >/dev/null); rc=$?
  if [ $rc -ne 0 ] && grep -qF -- "$part" <<<"$out"; then echo "ok   $what"
  else echo "FAIL $what (rc=$rc): $out"; failures=$((failures + 1)); fi
}
py=/usr/bin/python3; [ -x $py ] || py=python3
