"""`mbsa export --to mjcf` in MuJoCo: each exported model loads, and MuJoCo's own equality
constraint Jacobian at the keyframe `file` has the rank mbsa predicts: nv minus that rank is
mbsa's true mobility of the exported model (and of the mechanism it came from)."""

from pathlib import Path

import numpy as np
import pytest

FIXTURES = Path(__file__).resolve().parents[2] / "tests" / "fixtures" / "import"

# (case, the FILE and geometry arguments, equality rows expected, redundant rows expected)
CASES = [
    ("gazebo-four-bar", [str(FIXTURES / "four_bar.sdf")], 6, 3),
    ("bricard", ["@bricard"], 6, 1),
    ("n-four-bar-40", ["@n-four-bar-40"], 240, 0),
    ("cassie", [str(FIXTURES / "cassie.xml")], 12, 2),
    ("stewart", ["@stewart", "--geometry", "random", "--seed", "1"], 18, 0),
    ("planar-four-bar-in-3d", ["@rig-planar-four-bar-3d"], 6, 3),
]


def equality_rank(mujoco, path):
    """(nv, equality rows, their rank) of the model at its keyframe `file`."""
    model = mujoco.MjModel.from_xml_path(str(path))
    model.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    data = mujoco.MjData(model)
    key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, "file")
    assert key >= 0, "the export has a keyframe `file`"
    mujoco.mj_resetDataKeyframe(model, data, key)
    mujoco.mj_forward(model, data)
    rows = np.asarray(data.efc_J).reshape(data.nefc, model.nv)
    equality = rows[np.asarray(data.efc_type) == mujoco.mjtConstraint.mjCNSTR_EQUALITY]
    rank = int(np.linalg.matrix_rank(equality)) if equality.size else 0
    return model.nv, equality.shape[0], rank


@pytest.mark.parametrize("case,args,rows,redundant", CASES, ids=[c[0] for c in CASES])
def test_mujoco_equality_rank_gives_mbsas_true_mobility(
    cli, cli_json, tmp_path, case, args, rows, redundant
):
    mujoco = pytest.importorskip("mujoco", reason="mujoco is not installed")
    out = tmp_path / f"{case}.xml"
    code, _, err = cli("export", *args, "--to", "mjcf", "-o", str(out))
    assert code == 0, err
    assert ("redundant constraint row(s)" in err) == (redundant > 0), err
    nv, n_rows, rank = equality_rank(mujoco, out)
    assert (n_rows, n_rows - rank) == (rows, redundant)
    exported = cli_json("rigid", str(out), "--method", "geometric", "--format", "json")
    assert nv - rank == exported["mobility"]
    assert exported["redundant"] == redundant
    # The mechanism it came from (at the same geometry) has the same true mobility.
    geometry = args[1:] if len(args) > 1 else []
    source = cli_json("rigid", args[0], *geometry, "--method", "geometric", "--format", "json")
    assert source["mobility"] == exported["mobility"]


# (case, the FILE to repair): `mbsa repair --apply 1`, then `mbsa export --to mjcf`. The
# N-four-bar in 3D is repaired and checked in tests/it/repair.rs (its repair is the slow one).
REPAIRED = [
    ("gazebo-four-bar", str(FIXTURES / "four_bar.sdf")),
    ("bricard", "@bricard"),
    ("cassie", str(FIXTURES / "cassie.xml")),
    ("stewart-sps", str(FIXTURES.parent / "repair" / "stewart-sps.toml")),
    ("planar-four-bar-in-3d", "@rig-planar-four-bar-3d"),
]


@pytest.mark.parametrize("case,source", REPAIRED, ids=[c[0] for c in REPAIRED])
def test_repaired_models_export_without_a_redundant_row(cli, cli_json, tmp_path, case, source):
    """The repaired model's MJCF: MuJoCo's equality rows are independent at the keyframe and
    nv minus their rank is the true mobility mbsa gives the exported model."""
    mujoco = pytest.importorskip("mujoco", reason="mujoco is not installed")
    repaired = tmp_path / f"{case}.toml"
    code, _, err = cli("repair", source, "--apply", "1", "-o", str(repaired))
    assert code == 0, err
    out = tmp_path / f"{case}.xml"
    code, _, err = cli("export", str(repaired), "--to", "mjcf", "-o", str(out))
    assert code == 0, err
    assert "redundant constraint row(s)" not in err, err
    nv, n_rows, rank = equality_rank(mujoco, out)
    assert rank == n_rows
    exported = cli_json("rigid", str(out), "--method", "geometric", "--format", "json")
    assert exported["redundant"] == 0
    assert nv - rank == exported["mobility"]
