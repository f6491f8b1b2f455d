#!/usr/bin/env bash
# Runs one mbsa binary over every bundled mechanism and import fixture through every command
# (table and JSON) and writes each run's standard output, standard error and exit code to DIR.
# Two such directories compared with `diff -r` show every change of behaviour between builds:
#   scripts/compare-outputs.sh old/mbsa /tmp/before
#   scripts/compare-outputs.sh target/release/mbsa /tmp/after
#   diff -r /tmp/before /tmp/after
set -euo pipefail
bin=$(realpath "$1"); out=$2
cd "$(dirname "$0")/.."
rm -rf "$out"; mkdir -p "$out"
files=()
for f in mechanisms/*.toml; do files+=("$f"); done
for f in tests/fixtures/import/*.{xml,sdf,urdf,osim} tests/fixtures/closure/*.toml; do
  case "$f" in *include_forearm.xml|*include_defaults.xml) continue ;; esac
  files+=("$f")
done
cmds=(
  "mobility" "mobility --format json"
  "analyze" "analyze --format json" "analyze --count-only"
  "analyze --geometry random --seed 3 --format json"
  "dot" "dot --view structure" "dot --view topology"
  "rigid" "rigid --format json" "rigid --method counting --format json"
  "rigid --with-inputs --method geometric --format json" "rigid --finite"
  "transform --limit 30" "transform --limit 30 --format json"
  "solve" "solve --format json" "solve --global" "solve --global --format json"
  "assemble" "check"
)
jobs=()
for f in "${files[@]}"; do
  case "$f" in *.xml|*.sdf|*.urdf|*.osim) jobs+=("$f|import") ;; esac
  for c in "${cmds[@]}"; do jobs+=("$f|$c"); done
done
run_one() {
  local f=${1%%|*} c=${1#*|}
  local name; name=$(printf '%s__%s' "${f//\//_}" "${c// /_}")
  local sub=${c%% *} rest=""
  [ "$sub" != "$c" ] && rest=${c#* }
  # shellcheck disable=SC2086
  timeout 60 "$bin" $sub "$f" $rest >"$out/$name.out" 2>"$out/$name.err" </dev/null
  echo $? >"$out/$name.rc"
}
export -f run_one; export bin out
printf '%s\n' "${jobs[@]}" | xargs -P "${JOBS:-2}" -I{} bash -c 'run_one "$@"' _ {}
echo "${#jobs[@]} runs written to $out"
