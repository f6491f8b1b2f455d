"""Shared fixtures: the `mbsa` binary the Python results are compared with."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _binary() -> Path:
    if os.environ.get("MBSA_BIN"):
        return Path(os.environ["MBSA_BIN"])
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return target / "debug" / "mbsa"


@pytest.fixture(scope="session")
def cli():
    """Run the `mbsa` binary: (exit code, stdout, stderr)."""
    binary = _binary()
    if not binary.exists():
        pytest.skip(f"no mbsa binary at {binary}: build it (cargo build) or set MBSA_BIN")

    def run(*args):
        p = subprocess.run([str(binary), *args], capture_output=True, text=True, cwd=ROOT)
        return p.returncode, p.stdout, p.stderr

    return run


@pytest.fixture(scope="session")
def cli_json(cli):
    """The parsed JSON of a command that succeeds."""

    def run(*args):
        code, out, err = cli(*args)
        assert code == 0, err
        return json.loads(out)

    return run
