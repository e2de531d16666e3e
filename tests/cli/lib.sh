# Small assertion helpers for the CLI tests. Each test script sources this, calls the checks, then `finish`.
PASS=0
FAIL=0
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

ok() { PASS=$((PASS + 1)); }
bad() { FAIL=$((FAIL + 1)); echo "FAILED: $*" >&2; }

# run CMD...: sets RC, OUT, ERR
run() {
  set +e
  "$@" >"$TMP/out" 2>"$TMP/err"
  RC=$?
  set -e
  OUT=$(cat "$TMP/out")
  ERR=$(cat "$TMP/err")
}
expect_rc() { [ "$RC" = "$1" ] && ok || bad "$2: exit $RC, expected $1 (stderr: $ERR)"; }
expect_out() { grep -qF -- "$1" <<<"$OUT" && ok || bad "$2: stdout lacks '$1'"; }
expect_err() { grep -qF -- "$1" <<<"$ERR" && ok || bad "$2: stderr lacks '$1' (got: $ERR)"; }
expect_no_err() { if grep -qF -- "$1" <<<"$ERR"; then bad "$2: stderr has '$1' (got: $ERR)"; else ok; fi; }
expect_one_line_error() {
  local n
  n=$(printf '%s' "$ERR" | grep -c '' || true)
  [ "$n" = 1 ] && [[ "$ERR" == "actionshift: error: "* ]] && ok || bad "$1: expected one 'actionshift: error:' line, got: $ERR"
}
finish() {
  echo "$PASS passed, $FAIL failed"
  [ "$FAIL" = 0 ]
}
