#!/usr/bin/env bash
# The Python package in CI (docs/python.md).
#   deps: a virtual environment under the target directory with the build and test tools
#         (run it in the background while the Rust tests build).
#   test: build the extension into that environment, reusing the artifacts of
#         `cargo test --locked` (same profile, flags and features), then pytest and the notebook.
set -euo pipefail
cd "$(dirname "$0")/.."
target="${CARGO_TARGET_DIR:-target}"
venv="$target/py-venv"
step="${1:-}"

case "$step" in
deps)
  # --no-compile: no bytecode for the whole of sympy, matplotlib, ... while the Rust build
  # wants the cores (Python compiles what the tests import when they import it).
  python3 -m venv "$venv"
  "$venv/bin/python" -m pip install --quiet --no-compile --disable-pip-version-check --upgrade pip
  "$venv/bin/python" -m pip install --quiet --no-compile --disable-pip-version-check \
    'maturin>=1.5,<2' numpy pytest nbclient nbformat ipykernel matplotlib mujoco
  # PyRigi is optional: the interop tests skip, saying so, when it does not install.
  "$venv/bin/python" -m pip install --quiet --no-compile --disable-pip-version-check pyrigi ||
    echo "warning: pyrigi did not install; its parity tests will be skipped"
  touch "$venv/.deps-done"
  ;;
test)
  if [ ! -e "$venv/.deps-done" ]; then
    echo "error: run \`scripts/python-ci.sh deps\` first (it writes $venv)" >&2
    exit 2
  fi
  py="$venv/bin/python"
  # The extension as `cargo test --locked` builds the library: the same profile, flags and
  # environment (the caller's CARGO_*, RUSTFLAGS, RUSTC_WORKSPACE_WRAPPER), and the same
  # features: `-p mbsa --tests` selects the test targets, so the dependencies' features are
  # unified with the dev-dependencies' as in `cargo test` (built alone, the Python crate would
  # get other features and rebuild serde, clap, mbsa, ...; syn's: Cargo.toml,
  # [build-dependencies]). The tests are fresh: only PyO3 and the binding crate are compiled.
  start=$(date +%s)
  PYO3_PYTHON="$py" cargo build --locked -p mbsa -p mbsa-python --lib --tests \
    --features mbsa-python/extension-module 2>&1 | tee "$target/py-build.log"
  if grep -q "Compiling mbsa v" "$target/py-build.log"; then
    echo "warning: the extension's build compiled the library again: its dependencies' features" \
      "differ from the test build's (Cargo.toml, [build-dependencies])" >&2
  fi
  cp "$target/debug/lib_mbsa.so" python/mbsa/_mbsa.abi3.so
  # The package from the source tree (as `maturin develop` installs a python-source project).
  site=$("$py" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
  echo "$PWD/python" > "$site/mbsa.pth"
  echo "extension built in $(($(date +%s) - start)) s"
  # The parity tests run the binary `cargo test` built.
  MBSA_BIN="$target/debug/mbsa" "$py" -m pytest -q python/tests
  ;;
*)
  echo "usage: scripts/python-ci.sh deps|test" >&2
  exit 2
  ;;
esac
