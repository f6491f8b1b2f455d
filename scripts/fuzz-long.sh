#!/usr/bin/env bash
# The long fuzz campaign of docs/reliability.md: each target given (default: all) runs for
# FUZZ_RUNS executions (default 10^7) on a scratch copy of its committed corpus, one target per
# job, FUZZ_JOBS at a time (default 2). Stable toolchain with RUSTC_BOOTSTRAP=1, no sanitizer
# (see scripts/fuzz-ci.sh). Logs and the final statistics go to FUZZ_OUT (default
# target/fuzz-long/); a crash leaves its input under fuzz/artifacts/<target>/ and exit 1.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
RUNS=${FUZZ_RUNS:-10000000}
JOBS=${FUZZ_JOBS:-2}
OUT=${FUZZ_OUT:-$PWD/../target/fuzz-long}
export RUSTC_BOOTSTRAP=1
if ! cargo fuzz --version >/dev/null 2>&1; then
  cargo install cargo-fuzz --locked --quiet
fi
cargo fuzz build -s none --no-trace-compares
targets=("$@")
[ ${#targets[@]} -gt 0 ] || mapfile -t targets < <(cargo fuzz list)
mkdir -p "$OUT"
run() {
  local t=$1 start end
  mkdir -p "$OUT/$t.corpus"
  start=$(date +%s)
  if cargo fuzz run -s none --no-trace-compares "$t" "$OUT/$t.corpus" "corpus/$t" -- \
      -runs="$RUNS" -max_len=8192 -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      >"$OUT/$t.log" 2>&1; then
    status=ok
  else
    status=CRASH
  fi
  end=$(date +%s)
  local execs
  execs=$(grep -E "stat::number_of_executed_units" "$OUT/$t.log" | awk '{print $2}' | tail -1)
  echo "$t: $status, ${execs:-?} executions in $((end - start)) s" | tee -a "$OUT/summary.txt"
  [ "$status" = ok ]
}
export -f run
export RUNS OUT
printf '%s\n' "${targets[@]}" | xargs -P "$JOBS" -I{} bash -c 'run {}'
