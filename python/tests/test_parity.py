"""Every bundled mechanism: the Python reports are the CLI's `--format json`, key for key."""

import json
from pathlib import Path

import pytest

import mbsa

NAMES = mbsa.examples()


def test_the_examples_are_the_clis(cli):
    code, out, _ = cli("examples")
    assert code == 0
    listed = [line.split()[0][1:] for line in out.splitlines() if line.startswith("@")]
    assert listed == NAMES


def _same(cli, args, call):
    code, out, err = cli(*args)
    if code == 0:
        assert call() == json.loads(out), " ".join(args)
    else:
        with pytest.raises(mbsa.Error):
            call()


@pytest.mark.parametrize("name", NAMES)
def test_mobility_analyze_and_rigid_are_the_clis(cli, name):
    m = mbsa.load(f"@{name}")
    _same(cli, ["mobility", f"@{name}", "--format", "json"], m.mobility)
    _same(cli, ["analyze", f"@{name}", "--format", "json"], m.analyze)
    _same(cli, ["rigid", f"@{name}", "--format", "json"], m.rigid)


def test_options_reach_the_analyses(cli_json):
    m = mbsa.load("@rotor")
    assert m.analyze(inputs="1-2,1-13,13-15") == cli_json(
        "analyze", "@rotor", "--inputs", "1-2,1-13,13-15", "--format", "json"
    )
    assert m.rigid(method="counting") == cli_json(
        "rigid", "@rotor", "--method", "counting", "--format", "json"
    )
    assert m.analyze(geometry="random", seed=7) == cli_json(
        "analyze", "@rotor", "--geometry", "random", "--seed", "7", "--format", "json"
    )
    b = mbsa.load("@rig-bennett")
    assert b.rigid(finite=True) == cli_json("rigid", "@rig-bennett", "--finite", "--format", "json")


def test_transform_placements_are_the_clis_lines(cli):
    code, out, err = cli("transform", "@rotor", "--limit", "20", "--format", "jsonl")
    assert code == 0, err
    lines = [json.loads(line) for line in out.splitlines()]
    placements = mbsa.load("@rotor").transform(limit=20)
    assert list(placements) + [placements.summary] == lines
    assert len(placements) == len(lines) - 1


def test_a_floating_base_is_fixed_as_the_cli_fixes_it(cli):
    delta = str(Path(__file__).resolve().parents[2] / "tests/fixtures/import/delta_robot.sdf")
    m = mbsa.load(delta)
    for base, flags in [("auto", []), ("free", ["--keep-free-base"]), ("fixed", ["--fix-base"])]:
        code, out, err = cli("transform", delta, "--limit", "5", "--format", "jsonl", *flags)
        assert code == 0, err
        lines = [json.loads(line) for line in out.splitlines()]
        placements = m.transform(limit=5, base=base)
        assert list(placements) + [placements.summary] == lines, base
        assert ("fixed_base" in placements.summary) == (base != "free"), base
    with pytest.raises(mbsa.Error):
        m.transform(limit=5, base="floating")


def test_solve_and_sweep_are_the_clis(cli_json):
    m = mbsa.load("@slider-crank-geometry")
    r = m.solve(set={"O": 30})
    assert r == cli_json("solve", "@slider-crank-geometry", "--set", "O=30", "--format", "json")
    assert r.translations.shape == (len(r["poses"]), 3)
    assert r.quaternions.shape == (len(r["poses"]), 4)
    s = m.sweep("O", 0, 360, 30)
    assert s == cli_json(
        "solve", "@slider-crank-geometry", "--sweep", "O=0.0..360.0:30.0", "--format", "json"
    )
    n = len(s["steps"])
    assert s.values.tolist() == [step["value"] for step in s["steps"]]
    assert s.translations.shape == (n, len(s.bodies), 3)
    assert s.joint_values["O"].shape == (n, 1)


def test_to_toml_reads_back_to_the_same_analysis():
    m = mbsa.load("@rotor")
    again = mbsa.load(m.to_toml(), format="toml")
    assert again.analyze()["groups"] == m.analyze()["groups"]


def test_analyses_run_in_threads_with_the_same_answers():
    from concurrent.futures import ThreadPoolExecutor

    names = ["rotor", "stewart", "rig-double-banana", "hexapod-rss"]
    alone = [mbsa.load(f"@{n}").rigid() for n in names]
    with ThreadPoolExecutor(max_workers=4) as pool:
        together = list(pool.map(lambda n: mbsa.load(f"@{n}").rigid(), names))
    assert together == alone


@pytest.mark.parametrize("name", ["rig-planar-four-bar-3d", "bricard", "hexapod-rss", "n-four-bar-40"])
def test_repair_is_the_clis_and_the_repaired_model_is_well_posed(cli, name):
    m = mbsa.load(f"@{name}")
    _same(cli, ["repair", f"@{name}", "--format", "json"], lambda: m.repair())
    report = None
    try:
        report = m.repair()
    except mbsa.Error:
        return
    if not report["candidates"]:
        return
    fixed = m.repaired(1)
    code, out, _ = cli("repair", f"@{name}", "--apply", "1")
    assert code == 0
    assert fixed.to_toml() == mbsa.load(out, format="toml").to_toml()
    rigid = fixed.rigid(method="geometric")
    assert rigid["redundant"] == 0
    assert rigid["mobility"] == report["before"]["mobility"]
