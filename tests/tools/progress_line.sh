#!/usr/bin/env bash
# The tools' progress line (common/util/progress.hpp, docs/tools.md "Progress"): with stderr
# sent to a file it is not drawn (no '\r' anywhere), with --progress it is, on stderr only, and
# ends with the final line of the whole count; stdout holds the same lines either way.
# `teleop_bench robot --quick --steps 100`: its 7 cases in about a second.
#
#   progress_line.sh BUILD_DIR
set -u
build="$1"
bench="$build/tests/bench/teleop_bench"
fail() {
  echo "FAIL: $*"
  exit 1
}
[ -x "$bench" ] || fail "$bench not built"
tmp="$(mktemp -d /tmp/teleop_progress.XXXXXX)"
trap 'rm -rf "$tmp"' EXIT
cr=$'\r'
run() { "$bench" robot --quick --steps 100 --no-chart "$@"; }

# stderr is a file: quiet
run --out "$tmp/a" >"$tmp/a.out" 2>"$tmp/a.err" ||
  fail "teleop_bench robot exited $?: $(cat "$tmp/a.err")"
grep -q "$cr" "$tmp/a.err" &&
  fail "a progress line on stderr although it is a file: $(cat -A "$tmp/a.err")"
grep -q "robot:" "$tmp/a.err" && fail "progress text on stderr although it is a file"
grep -q "$cr" "$tmp/a.out" && fail "a carriage return on stdout"

# --progress: drawn on stderr, the final line counts every case
run --progress --out "$tmp/b" >"$tmp/b.out" 2>"$tmp/b.err" ||
  fail "teleop_bench robot --progress exited $?"
grep -q "$cr" "$tmp/b.err" ||
  fail "no progress line on stderr with --progress: $(cat -A "$tmp/b.err")"
last="$(tr "$cr" '\n' <"$tmp/b.err" | grep -v '^ *$' | tail -n 1)"
case "$last" in
"robot: 7/7 cases (100.0 %), "*" cases/s, done in "*) ;;
*) fail "the last progress line is '$last', not the final count of the 7 cases" ;;
esac
grep -q "$cr" "$tmp/b.out" && fail "a carriage return on stdout with --progress"
# stdout: the same lines, numbers aside (they are timings)
strip() { sed -E -e 's/[0-9]+(\.[0-9]+)?/N/g' -e 's/ +/ /g' "$1"; }
[ "$(wc -l <"$tmp/a.out")" -ge 7 ] || fail "stdout has too few lines: $(cat "$tmp/a.out")"
[ "$(strip "$tmp/a.out")" = "$(strip "$tmp/b.out")" ] ||
  fail "stdout differs with --progress: $(diff <(strip "$tmp/a.out") <(strip "$tmp/b.out"))"
echo "progress line: quiet on a file; with --progress '$last' on stderr; stdout unchanged"
