"""Errors: located as the CLI locates them; the budget; the README's one-liner."""

import json
import subprocess
import sys

import pytest

import mbsa

BAD = 'name = "broken"\nspace = "planar"\nframe = "1"\n\n[[joint]]\nid = "A"\ntype = "Q"\nbodies = ["1", "2"]\n'


def test_input_error_is_located_as_the_cli_locates_it(cli, tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text(BAD)
    code, out, _ = cli("check", str(path), "--format", "json")
    assert code == 2
    record = json.loads(out)["files"][0]["error"]
    with pytest.raises(mbsa.InputError) as e:
        mbsa.load(str(path))
    err = e.value
    assert (err.file, err.line, err.column) == (record["file"], record["line"], record["col"])
    assert err.message == record["message"]
    assert (err.line, err.column) == (7, 8)
    # The diagnostic on standard error points at the same place.
    code, _, stderr = cli("analyze", str(path))
    assert code == 2 and f"[{path}:7:8]" in stderr
    assert f"[{path}:7:8]" in err.rendered
    assert str(err).startswith(f"{path}:7:8: ")


def test_text_is_named_string():
    with pytest.raises(mbsa.InputError) as e:
        mbsa.load(BAD)
    assert (e.value.file, e.value.line) == ("<string>", 7)


def test_unknown_example_and_missing_file():
    with pytest.raises(mbsa.InputError, match="no bundled example named `rotr`"):
        mbsa.load("@rotr")
    with pytest.raises(mbsa.InputError, match="cannot read"):
        mbsa.load("no/such/file.toml")


def test_budget_raises():
    m = mbsa.load("@stewart")
    with pytest.raises(mbsa.BudgetExceeded):
        m.transform(max_work=1000)
    with pytest.raises(mbsa.BudgetExceeded):
        mbsa.load("@micro-manipulator").analyze(exhaustive=True, max_work=10)


def test_readme_one_liner_prints_determined():
    code = "import mbsa; print(mbsa.load('@rotor').analyze()['status'])"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout == "determined\n"
