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
  python3 -m venv "$venv"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check --upgrade pip
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check \
    'maturin>=1.5,<2' numpy pytest nbclient nbformat ipykernel matplotlib mujoco
  # PyRigi is optional: the interop tests skip, saying so, when it does not install.
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check pyrigi ||
    echo "warning: pyrigi did not install; its parity tests will be skipped"
  touch "$venv/.deps-done"
  ;;
test)
  echo "(test step to be written)"
  ;;
*)
  echo "usage: scripts/python-ci.sh deps|test" >&2
  exit 2
  ;;
esac
