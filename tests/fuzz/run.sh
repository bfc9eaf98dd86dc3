#!/usr/bin/env bash
# One bounded libFuzzer run of the fuzz suite: usage run.sh FUZZER SEEDS ARTIFACTS SECONDS.
# Starts from the committed seed corpus, keeps new inputs in a scratch corpus, and fails on any
# crash, sanitizer report, leak, slow input (> 10 s) or memory use above 1 GB; the input at fault
# is left in ARTIFACTS (crash-*, leak-*, timeout-*, oom-*) to become a regression fixture.
set -u
fuzzer=$1 seeds=$2 artifacts=$3 seconds=$4
[ -x "$fuzzer" ] || { echo "no fuzzer at $fuzzer"; exit 1; }
[ -d "$seeds" ] || { echo "no seed corpus at $seeds"; exit 1; }
corpus=$(mktemp -d)
log=$(mktemp)
trap 'rm -rf "$corpus" "$log"' EXIT
mkdir -p "$artifacts"

# -close_fd_mask=2 silences the loaders' one-line errors; libFuzzer and the sanitizers keep
# reporting through their own copy of stderr.
"$fuzzer" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=1024 -close_fd_mask=2 \
  -print_final_stats=1 -artifact_prefix="$artifacts/" "$corpus" "$seeds" >"$log" 2>&1
status=$?
runs=$(awk '/^stat::number_of_executed_units:/ { print $NF }' "$log")
if [ "$status" != 0 ]; then
  tail -n 80 "$log"
  echo "FAIL: $(basename "$fuzzer") exited $status after ${runs:-?} executions; input kept in $artifacts"
  exit 1
fi
grep -E "^(INFO: seed corpus|#[0-9]+[[:space:]]+DONE)" "$log"
echo "$(basename "$fuzzer"): ${runs:-?} executions in $seconds s, corpus $(ls "$corpus" | wc -l) new inputs, no crash"
