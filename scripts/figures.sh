#!/usr/bin/env bash
# Regenerates the pictures in docs/img/ (README and docs) from the bundled examples.
# Needs Graphviz (`apt-get install graphviz`).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
mbsa=target/release/mbsa
$mbsa dot @rotor | dot -Tsvg > docs/img/rotor-diagram.svg
$mbsa dot @rotor --view structure | dot -Tsvg > docs/img/rotor-structure.svg
$mbsa dot @micro-manipulator --view structure | dot -Tsvg > docs/img/micro-manipulator-structure.svg
echo "wrote docs/img/rotor-diagram.svg, rotor-structure.svg, micro-manipulator-structure.svg"
