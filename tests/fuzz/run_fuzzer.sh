#!/bin/sh
# One fuzzer's ctest run: replay every file of the committed corpus (each a regression: it must
# not crash), then fuzz for SECONDS starting from it into a scratch corpus, with the dictionary
# when there is one. Crashing inputs are written into WORK/crashes/. Prints libFuzzer's stats.
# With RUNS, the run is deterministic (seed 1, at most RUNS inputs, SECONDS only as a cap): the
# same inputs on every machine, so a failure is a regression, not luck.
#   run_fuzzer.sh FUZZER CORPUS WORK SECONDS [RUNS]
set -eu
fuzzer=$1 corpus=$2 work=$3 seconds=$4 runs=${5:--1}
name=$(basename "$fuzzer")
dict=$(dirname "$corpus")/../${name#fuzz_}.dict
rm -rf "$work/corpus"
mkdir -p "$work/corpus" "$work/crashes"
dict_flag=""
[ -f "$dict" ] && dict_flag="-dict=$dict"
echo "== $name: replaying $(ls "$corpus" | wc -l) corpus files"
"$fuzzer" -runs=0 $dict_flag "$corpus"
seed_flags=""
[ "$runs" != "-1" ] && seed_flags="-seed=1 -runs=$runs"
echo "== $name: fuzzing ${runs#-1} runs, at most $seconds s"
# -max_len: scene files and meshes are small; -timeout: one input taking 10 s is a hang
# shellcheck disable=SC2086
"$fuzzer" $seed_flags -max_total_time="$seconds" -max_len=8192 -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 -artifact_prefix="$work/crashes/" $dict_flag "$work/corpus" "$corpus"
