#!/usr/bin/env bash
# A campaign killed with SIGKILL in the middle resumes where it stopped: run again into the same
# folder it runs only the runs without a result file, and its table equals, byte for byte, the
# table of the same campaign run without interruption (on another thread count).
#
#   campaign_resume.sh BUILD_DIR
set -u
build="$1"
campaign="$build/client/campaign/teleop_campaign"
fail() {
  echo "FAIL: $*"
  exit 1
}
[ -x "$campaign" ] || fail "$campaign not built"
tmp="$(mktemp -d /tmp/teleop_resume.XXXXXX)"
pid=""
cleanup() {
  [ -n "$pid" ] && kill -9 "$pid" 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT

# 120 point runs of the whole press-slip task
cat >"$tmp/c.yaml" <<EOF
name: resume-check
model: point
sweeps:
  - name: s
    scheme: [position-position, force-position, tdpa]
    environment: [sphere, wall]
    stiffness_n_per_m: 2000
    gain: [0, 800]
    delay_ms: {from: 0, to: 180, step: 20}
EOF
"$campaign" run "$tmp/c.yaml" --out "$tmp/whole" --no-chart --jobs 2 >/dev/null ||
  fail "uninterrupted run failed"

"$campaign" run "$tmp/c.yaml" --out "$tmp/killed" --no-chart --jobs 1 >/dev/null &
pid=$!
for _ in $(seq 600); do
  n="$(ls "$tmp/killed/runs" 2>/dev/null | grep -c '\.csv$')"
  [ "$n" -ge 5 ] && break
  sleep 0.01
done
kill -9 "$pid"
wait "$pid" 2>/dev/null
pid=""
done_before="$(ls "$tmp/killed/runs" | grep -c '\.csv$')"
[ "$done_before" -ge 5 ] && [ "$done_before" -lt 120 ] ||
  fail "expected the kill to land mid-campaign; $done_before of 120 runs were done"
[ ! -f "$tmp/killed/results.csv" ] || fail "a killed campaign must not have a table"
out="$("$campaign" run "$tmp/c.yaml" --out "$tmp/killed" --no-chart --jobs 2)" ||
  fail "resumed run failed"
echo "$out" | grep -q "120 runs, $done_before done before, $((120 - done_before)) ran" ||
  fail "the resumed run did not skip the $done_before finished runs: $out"
cmp "$tmp/whole/results.csv" "$tmp/killed/results.csv" ||
  fail "the resumed table differs from the uninterrupted one"
echo "PASS: killed after $done_before of 120 runs; the resumed table equals the uninterrupted one"
