# Shared check of the CLI scripts' error paths; sourced, not run (not a test of its own).
#
# expect_exit <code> <pattern> <stderr file> <command...>
#   Runs the command (stdout discarded, stderr kept in <stderr file>). It must exit with exactly
#   <code>: 1 for an error, 2 for a usage error. Any other non-zero code is a crash, an abort or a
#   sanitizer's report (tools/run_tests.sh has ASan exit 86 and UBSan 87), which a check of
#   "non-zero" would pass. Its stderr must match <pattern> (grep's basic regular expression; ""
#   checks nothing more). Exits the script with status 1 otherwise.
expect_exit() {
  local want=$1 pattern=$2 errf=$3 rc=0
  shift 3
  "$@" >/dev/null 2>"$errf" || rc=$?
  if [ "$rc" -ne "$want" ]; then
    echo "FAIL: '$*' exited $rc, expected $want; stderr: $(cat "$errf")" >&2
    exit 1
  fi
  if [ -n "$pattern" ] && ! grep -q -- "$pattern" "$errf"; then
    echo "FAIL: '$*': stderr does not match '$pattern': $(cat "$errf")" >&2
    exit 1
  fi
}
