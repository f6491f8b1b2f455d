#!/usr/bin/env bash
# Short fuzz run of every cargo-fuzz target (docs/reliability.md). Stable toolchain with
# RUSTC_BOOTSTRAP=1 (cargo-fuzz passes nightly -Z flags); no sanitizer (the crate forbids
# unsafe code, and libFuzzer alone catches panics, aborts, timeouts and memory blow-ups).
# FUZZ_SECONDS per target (default 20). The committed corpus is only read: new inputs go to
# a scratch directory. Exit 1 on a crash, with the reproducing input's path.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
SECS=${FUZZ_SECONDS:-20}
export RUSTC_BOOTSTRAP=1
if ! cargo fuzz --version >/dev/null 2>&1; then
  echo "== installing cargo-fuzz"
  cargo install cargo-fuzz --locked --quiet
fi
echo "== building fuzz targets"
cargo fuzz build -s none
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
status=0
for t in $(cargo fuzz list); do
  mkdir -p "$work/$t"
  echo "== fuzz $t for ${SECS}s"
  if ! cargo fuzz run -s none "$t" "$work/$t" "corpus/$t" -- \
      -max_total_time="$SECS" -max_len=8192 -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 >"$work/$t.log" 2>&1; then
    status=1
    grep -E "panicked|ERROR|SUMMARY|Test unit written|Base64" "$work/$t.log" | head -20 || true
    echo "FAILED: fuzz target $t found a crash (input under fuzz/artifacts/$t/)"
  fi
  grep -E "^Done|stat::number_of_executed_units" "$work/$t.log" || true
done
exit $status
