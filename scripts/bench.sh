#!/usr/bin/env bash
# Reproduce every figure of docs/benchmarks.md in one command:
#
#   scripts/bench.sh            # build, cargo bench, generate files, time the binary, update docs
#   scripts/bench.sh --no-bench # reuse target/bench/divan.txt from an earlier run
#
# Steps: release build; `cargo bench --bench structure` (divan, a few minutes) into
# target/bench/divan.txt and `cargo bench --bench analyses` (transformations, rigidity) into
# target/bench/divan-analyses.txt; then scripts/bench_report.py generates mechanism files with
# `mbsa generate`, measures peak memory (/usr/bin/time -v) and end-to-end time (hyperfine when
# installed, else a repeated loop) of `mbsa analyze --format json`, and rewrites the generated
# blocks of docs/benchmarks.md and the plot docs/benchmarks-growth.svg.
# Needs: cargo, python3 (standard library only), GNU time; hyperfine optional
# (apt-get install hyperfine). Exhaustive-search budget: MBSA_EXHAUSTIVE_BUDGET seconds (10).
set -euo pipefail
cd "$(dirname "$0")/.."
out=target/bench
mkdir -p "$out"

cargo build --release --bin mbsa
if [[ "${1:-}" != "--no-bench" ]]; then
    cargo bench --bench structure | tee "$out/divan.txt"
    cargo bench --bench analyses | tee "$out/divan-analyses.txt"
fi
python3 scripts/bench_report.py --bin target/release/mbsa --out "$out" --docs docs/benchmarks.md
