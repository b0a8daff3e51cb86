#!/usr/bin/env bash
# The tools' progress line (common/util/progress.hpp, docs/tools.md "Progress"): with stderr
# sent to a file it is not drawn (no '\r' anywhere), with --progress it is, on stderr only, and
# ends with the final line of the whole count; stdout holds the same lines either way.
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

# stderr is a file: quiet
"$bench" delay --quick --no-chart --out "$tmp/a" >"$tmp/a.out" 2>"$tmp/a.err" ||
  fail "teleop_bench delay --quick exited $?: $(cat "$tmp/a.err")"
grep -q "$cr" "$tmp/a.err" && fail "a progress line on stderr although it is a file: $(cat -A "$tmp/a.err")"
grep -q "$cr" "$tmp/a.out" && fail "a carriage return on stdout"
grep -q "delay:" "$tmp/a.err" && fail "progress text on stderr although it is a file"

# --progress: drawn on stderr, the final line counts every run of the sweep
"$bench" delay --quick --no-chart --progress --out "$tmp/b" >"$tmp/b.out" 2>"$tmp/b.err" ||
  fail "teleop_bench delay --quick --progress exited $?"
runs="$(sed -n 's/^delay sweep: \([0-9]*\) runs.*/\1/p' "$tmp/b.out")"
[ -n "$runs" ] || fail "no 'delay sweep: N runs' line on stdout: $(cat "$tmp/b.out")"
last="$(tr "$cr" '\n' <"$tmp/b.err" | grep -v '^ *$' | tail -n 1)"
case "$last" in
"delay: $runs/$runs runs (100.0 %), "*" runs/s, done in "*) ;;
*) fail "the last progress line is '$last', not the final count of $runs runs" ;;
esac
grep -q "$cr" "$tmp/b.out" && fail "a carriage return on stdout with --progress"
# stdout: the same lines (the figures that are timings aside)
strip() { sed -e 's/[0-9.]* s;/T/' -e 's/p[0-9]* [0-9.]* us/P/g' -e 's/[0-9.]* \/ [0-9.]*/P/g' "$1"; }
[ "$(strip "$tmp/a.out")" = "$(strip "$tmp/b.out")" ] ||
  fail "stdout differs with --progress: $(diff <(strip "$tmp/a.out") <(strip "$tmp/b.out"))"

echo "progress line: quiet on a file, $runs/$runs with --progress, stdout unchanged"
