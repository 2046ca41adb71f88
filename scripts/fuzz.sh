#!/usr/bin/env bash
# Runs the libFuzzer targets of tests/fuzz/ (built by scripts/build.sh fuzz) on their seed corpora.
# Usage: scripts/fuzz.sh [SECONDS_PER_TARGET [target...]]     (default: 20 s, every target)
#        FUZZ_RUNS=N scripts/fuzz.sh 0 stl                     (a fixed number of executions)
# FUZZ_MAX_LEN (default 65536) caps an input's size in bytes: the long budgets of the slower
# readers use a smaller cap (docs/results/reliability.md), since inputs grow to it and the rate falls.
# FUZZ_SEED (default 1) seeds libFuzzer's mutations: with FUZZ_RUNS the run is reproducible, which
# is how scripts/test.sh (CI) runs it; the long budgets use time and other seeds.
# New inputs go to build/fuzz/corpus/<target> (the seeds in tests/fuzz/corpus/<target> are only
# read); a crash leaves its input in build/fuzz/artifacts/ and makes this script exit 1.
# Each run prints libFuzzer's final stats (executions, cov, ft) — docs/results/reliability.md.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-20}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(stl obj scene device_model calibration_log session)
declare -A dict=([stl]=stl [obj]=obj [scene]=json [device_model]=json [calibration_log]=csv
                [session]=session)
mkdir -p build/fuzz/artifacts
status=0
for t in "${targets[@]}"; do
  bin=build/fuzz/fuzz/${t}_fuzz
  [ -x "$bin" ] || { echo "fuzz.sh: $bin not built (scripts/build.sh fuzz)" >&2; exit 2; }
  [ -n "${dict[$t]:-}" ] || { echo "fuzz.sh: unknown target '$t'" >&2; exit 2; }
  mkdir -p "build/fuzz/corpus/$t"
  budget=(-max_total_time="$seconds" -seed="${FUZZ_SEED:-1}")
  [ -n "${FUZZ_RUNS:-}" ] && budget=(-runs="$FUZZ_RUNS" -seed="${FUZZ_SEED:-1}")
  echo "== fuzz $t (${FUZZ_RUNS:-$seconds s})"
  # -timeout: one input may take at most 10 s (a hang is a finding); -rss_limit_mb: 2 GB.
  if ! "$bin" "${budget[@]}" -timeout=10 -rss_limit_mb=2048 -max_len="${FUZZ_MAX_LEN:-65536}" -print_final_stats=1 \
       -dict="tests/fuzz/${dict[$t]}.dict" -artifact_prefix="build/fuzz/artifacts/${t}-" \
       "build/fuzz/corpus/$t" "tests/fuzz/corpus/$t" > "build/fuzz/$t.log" 2>&1; then
    status=1
    echo "fuzz.sh: $t FAILED (build/fuzz/$t.log):" >&2
    grep -E "ERROR|SUMMARY|Test unit written|==[0-9]+==" "build/fuzz/$t.log" | head -20 >&2
  fi
  grep -E "^#[0-9]+.*DONE|stat::number_of_executed_units|cov:" "build/fuzz/$t.log" | tail -2
done
exit $status
