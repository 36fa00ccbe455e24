#!/usr/bin/env bash
# Every subcommand's --help exits 0 and prints its usage; a missing or unknown subcommand is a usage
# error (exit 2). Usage: bash help.sh <path-to-strata> <tests/data dir>
set -euo pipefail
STRATA=${1:?usage: help.sh <path-to-strata> <tests/data dir>}

fail() { echo "FAIL: $*" >&2; exit 1; }

out=$("$STRATA" --help) || fail "strata --help exited non-zero"
for sub in reconstruct stats generate demo; do
  grep -q "$sub" <<<"$out" || fail "strata --help does not list '$sub'"
  sub_out=$("$STRATA" "$sub" --help) || fail "strata $sub --help exited non-zero"
  grep -q "Usage: strata $sub" <<<"$sub_out" || fail "strata $sub --help prints no usage line"
done

# --version prints the SDK's version (CMakeLists.txt's project VERSION) and exits 0.
want=$(sed -n 's/^project(Strata VERSION \([0-9.]*\).*/\1/p' "$(dirname "$0")/../../CMakeLists.txt")
[ -n "$want" ] || fail "no project VERSION in CMakeLists.txt"
ver=$("$STRATA" --version) || fail "strata --version exited non-zero"
[ "$ver" = "strata $want" ] || fail "strata --version printed '$ver', expected 'strata $want'"

grep -q "cage" <<<"$out" || fail "strata --help does not list 'cage'"
sub_out=$("$STRATA" cage fit --help) || fail "strata cage fit --help exited non-zero"
grep -q "Usage: strata cage fit" <<<"$sub_out" || fail "strata cage fit --help prints no usage line"

# The benchmark programs beside strata: --help prints the usage and exits 0 (it does not run the
# benchmark); an option without its value is a usage error.
BIN=$(dirname "$STRATA")
for b in strata_bench strata_bench_drag strata_bench_subdiv strata_bench_layers; do
  [ -x "$BIN/$b" ] || fail "$b not built beside strata"
  b_out=$(timeout 60 "$BIN/$b" --help) || fail "$b --help exited non-zero"
  grep -q "usage: $b" <<<"$b_out" || fail "$b --help prints no usage line"
done
set +e
for cmd in "strata_bench --sizes" "strata_bench_drag --steps" "strata_bench_subdiv --points" "strata_bench_layers"; do
  timeout 60 "$BIN/"$cmd >/dev/null 2>&1; rc=$?
  [ "$rc" -eq 2 ] || fail "$cmd exited $rc, expected 2"
done
"$STRATA" >/dev/null 2>&1; rc=$?
[ "$rc" -eq 2 ] || fail "strata without a subcommand exited $rc, expected 2"
err=$("$STRATA" frobnicate 2>&1 >/dev/null); rc=$?
[ "$rc" -eq 2 ] || fail "strata frobnicate exited $rc, expected 2"
grep -q "^strata: error: " <<<"$err" || fail "usage error message not prefixed 'strata: error: ': $err"
"$STRATA" reconstruct >/dev/null 2>&1; rc=$?
[ "$rc" -eq 2 ] || fail "strata reconstruct without options exited $rc, expected 2"
set -e
echo "help: all checks passed"
