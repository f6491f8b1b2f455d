#!/usr/bin/env bash
# Short fuzz run of every libFuzzer target in fuzz/ (docs/reliability.md). Built by cargo
# directly with the instrumentation `cargo fuzz build -s none` adds, so that a fresh machine
# needs no cargo-fuzz to install (about a minute) and the build may use every codegen unit
# (cargo fuzz forces one in release: the slowest step of CI). No sanitizer: the crate forbids
# unsafe code, and libFuzzer alone catches panics, aborts, timeouts and memory blow-ups.
# FUZZ_SECONDS per target (default 20). The committed corpus is only read: new inputs go to
# a scratch directory. Exit 1 on a crash, with the reproducing input's path.
#   scripts/fuzz-ci.sh          build, then run every target
#   scripts/fuzz-ci.sh build    build only (CI starts it beside the other steps)
#   scripts/fuzz-ci.sh run      run only, on an earlier build
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
SECS=${FUZZ_SECONDS:-20}
triple=$(rustc -vV | sed -n 's/^host: //p')
flags="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4"
flags+=" -Cllvm-args=-sanitizer-coverage-inline-8bit-counters"
flags+=" -Cllvm-args=-sanitizer-coverage-pc-table"
flags+=" -Cllvm-args=-sanitizer-coverage-trace-compares"
flags+=" -Cllvm-args=-simplifycfg-branch-fold-threshold=0"
flags+=" -Cllvm-args=-sanitizer-coverage-stack-depth --cfg fuzzing"
step=${1:-all}
if [ "$step" != run ]; then
  echo "== building fuzz targets"
  # --target keeps RUSTFLAGS away from build scripts, as cargo fuzz does. FUZZ_OPT_LEVEL
  # (default: the profile's 1) 0 halves the build's CPU time, for runs of a few seconds
  # where the build is the cost (.ci/run).
  CARGO_PROFILE_RELEASE_OPT_LEVEL=${FUZZ_OPT_LEVEL:-1} RUSTFLAGS="$flags" \
    cargo build --release --locked --bins --target "$triple"
fi
[ "$step" = build ] && exit 0
bin=${CARGO_TARGET_DIR:-target}/$triple/release
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# One target per core at a time: each gets its SECS of a core.
jobs=$(nproc 2>/dev/null || echo 2)
fuzz_one() {
  local t=$1
  mkdir -p "$work/$t" "artifacts/$t"
  if ! "$bin/$t" "$work/$t" "corpus/$t" -artifact_prefix="artifacts/$t/" \
      -max_total_time="$SECS" -max_len=8192 -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 >"$work/$t.log" 2>&1; then
    touch "$work/$t.failed"
  fi
}
targets=$(sed -n '/^\[\[bin\]\]/,/^path/s/^name = "\(.*\)"/\1/p' Cargo.toml)
echo "== fuzz $(echo $targets | wc -w) targets for ${SECS}s each, $jobs at a time"
running=0
for t in $targets; do
  fuzz_one "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n || true
    running=$((running - 1))
  fi
done
wait
status=0
for t in $targets; do
  echo "== fuzz $t"
  if [ -e "$work/$t.failed" ]; then
    status=1
    grep -E "panicked|ERROR|SUMMARY|Test unit written|Base64" "$work/$t.log" | head -20 || true
    echo "FAILED: fuzz target $t found a crash (input under fuzz/artifacts/$t/)"
  fi
  grep -E "^Done|stat::number_of_executed_units" "$work/$t.log" || true
done
exit $status
