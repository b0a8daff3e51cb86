#!/usr/bin/env bash
# What a teleop_record killed with -9 loses: one server + master session (loopback profile,
# domain 104) recorded by two MCAP recorders; one is stopped normally, the other killed with -9
# 3.4, 3.7, 4.1 ... s into the session (another moment of its chunk each run). Both files are
# converted to SQLite (teleop_play --convert) and compared with python3's sqlite3: the samples
# the finished recording received before the kill, from the first sample the killed recorder
# heard of each writer on, that the recovered file lacks are what the kill lost. Prints, per
# run, the recovered chunks, the lost samples and the span they cover. No assertion: figures for
# docs/tools.md.
#   tests/bench/record_kill.sh [BUILD_DIR] [RUNS] [SCENE] [CHUNK_S]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-$root/build}"
runs="${2:-3}"
scene="${3:-$root/deploy/scenes/default.yaml}"
chunk_s="${4:-1}"
domain=104  # a benchmark domain (100+), not a test's
tmp="$(mktemp -d /tmp/teleop_record_kill.XXXXXX)"
trap 'rm -rf "$tmp"' EXIT
echo "scene $(basename "$scene"), --chunk-s $chunk_s, $runs runs, domain $domain"
for i in $(seq 1 "$runs"); do
  "$build/client/teleop_record" --domain $domain --out "$tmp/full$i.mcap" --quiet &
  full=$!
  "$build/client/teleop_record" --domain $domain --out "$tmp/killed$i.mcap" --chunk-s "$chunk_s" \
    --quiet &
  victim=$!
  sleep 1
  "$build/server/teleop_server" --domain $domain --duration 60 --scene "$scene" --quiet \
    >/dev/null 2>&1 &
  server=$!
  "$build/client/teleop_master" --domain $domain --duration 6 --quiet >/dev/null 2>&1 &
  master=$!
  # a kill at a different moment of the chunk each run
  sleep "$(awk -v i="$i" 'BEGIN {print 3 + 0.37 * i}')"
  kill -KILL $victim
  killed_ns=$(date +%s%N)
  wait $victim 2>/dev/null || true  # bash reports the kill on stderr
  wait $master || true
  kill -TERM $server; wait $server || true
  sleep 0.3
  kill -INT $full; wait $full || true
  info="$("$build/client/teleop_play" "$tmp/killed$i.mcap" --info)"
  "$build/client/teleop_play" "$tmp/full$i.mcap" --convert "$tmp/full$i.db" --quiet
  "$build/client/teleop_play" "$tmp/killed$i.mcap" --convert "$tmp/killed$i.db" --quiet
  /usr/bin/python3 - "$tmp/full$i.db" "$tmp/killed$i.db" "$killed_ns" "$i" \
    "$(grep -o '^  chunks *[0-9]*' <<<"$info" | awk '{print $2}')" <<'PY'
import sqlite3, sys
full, killed, killed_ns, run, chunks = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], sys.argv[5]
def keyed(path):
    db = sqlite3.connect(path)
    names = dict(db.execute("SELECT id, name FROM topics"))
    return {(names[t], w, s): r for t, w, s, r in
            db.execute("SELECT topic_id, writer_guid, writer_seq, receive_ns FROM samples")}
a, b = keyed(full), keyed(killed)
# a writer's samples count from the first one the killed recorder heard (the two recorders
# matched each writer at slightly different times)
first = {}
for t, w, s in b:
    first[(t, w)] = min(s, first.get((t, w), s))
before = {k: r for k, r in a.items() if r <= killed_ns and (k[0], k[1]) in first and
          k[2] >= first[(k[0], k[1])]}
lost = [r for k, r in before.items() if k not in b]
extra = [k for k in b if k not in a]
span = (max(lost) - min(lost)) / 1e9 if lost else 0.0
last = max(b.values()) if b else 0
print(f"run {run}: killed recording {len(b)} samples in {chunks} chunks; the finished one had "
      f"{len(before)} of those writers by the kill: {len(lost)} lost ({100 * len(lost) / max(1, len(before)):.1f} %), "
      f"spanning {span:.3f} s; last recovered sample {(killed_ns - last) / 1e9:.3f} s before the "
      f"kill; {len(extra)} samples not in the finished file")
PY
done
if command -v fastdds >/dev/null 2>&1; then fastdds shm clean >/dev/null 2>&1 || true; fi
