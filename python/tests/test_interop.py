"""Interop: PyRigi's rigidity answers and MuJoCo's constraint rank against mbsa's."""

from pathlib import Path

import numpy as np
import pytest

import mbsa

FIXTURES = Path(__file__).resolve().parents[2] / "tests" / "fixtures" / "import"


def _pyrigi_frameworks():
    frameworks = pytest.importorskip(
        "pyrigi.frameworkDB", reason="pyrigi is not installed: its parity tests are skipped"
    )
    out = {}
    # 2D: a triangle, a square (flexible), Laman frameworks; 3D: the tetrahedron (K4),
    # the octahedron, a flexible cube of bars.
    makers = {
        "Complete3": lambda: frameworks.Complete(3, dim=2),
        "Complete4_2d": lambda: frameworks.Complete(4, dim=2),
        "Cycle4": lambda: frameworks.Cycle(4, dim=2),
        "Cycle5": lambda: frameworks.Cycle(5, dim=2),
        "ThreePrism": lambda: frameworks.ThreePrism(),
        "ThreePrismFlexible": lambda: frameworks.ThreePrism(realization="flexible"),
        "Diamond": lambda: frameworks.Diamond(),
        "Square": lambda: frameworks.Square(),
        "K33plusEdge": lambda: frameworks.K33plusEdge(),
        "Complete4_3d": lambda: frameworks.Complete(4, dim=3),
        "Octahedron": lambda: frameworks.Octahedron(realization="Bricard_line"),
        "Cube": lambda: frameworks.Cube(),
    }
    for name, make in makers.items():
        try:
            out[name] = make()
        except (AttributeError, TypeError, ValueError):
            continue  # not in this PyRigi version
    return out


def _flexes(framework):
    m = mbsa.from_pyrigi(framework)
    g = m.rigid(method="geometric")
    bars = len(list(framework.graph.edges))
    mobility = g["mobility"]
    return mobility - bars if framework.dim == 3 else mobility


def test_pyrigi_rigidity_and_flexes_are_mbsas():
    frameworks = _pyrigi_frameworks()
    assert len(frameworks) >= 6, sorted(frameworks)
    for name, f in frameworks.items():
        flexes = _flexes(f)
        expected = len(f.nontrivial_inf_flexes(numerical=True))
        assert flexes == expected, name
        assert (flexes == 0) == f.is_inf_rigid(numerical=True), name


def test_pyrigi_bars_are_bodies_and_points_are_joints():
    pytest.importorskip("pyrigi", reason="pyrigi is not installed: its parity tests are skipped")
    from pyrigi import frameworkDB

    f = frameworkDB.Complete(4, dim=3)
    m = mbsa.from_pyrigi(f)
    assert len(m.joints) == 4 and len(m.bodies) == 6
    assert "type = \"S\"" in m.to_toml()


def test_cassie_mujoco_equality_rank_gives_mbsas_true_mobility():
    mujoco = pytest.importorskip("mujoco", reason="mujoco is not installed")
    path = FIXTURES / "cassie.xml"
    # The fixture keeps the kinematics only (no geoms, no inertials): MuJoCo needs masses,
    # which play no part in the constraint Jacobian.
    xml = path.read_text().replace(
        'autolimits="true"/>', 'autolimits="true" boundmass="1" boundinertia="0.1"/>', 1
    )
    model = mujoco.MjModel.from_xml_string(xml)
    model.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    rows = np.asarray(data.efc_J).reshape(data.nefc, model.nv)
    equality = rows[np.asarray(data.efc_type) == mujoco.mjtConstraint.mjCNSTR_EQUALITY]
    rank = np.linalg.matrix_rank(equality)
    assert (equality.shape[0], rank) == (12, 10)
    # The importer's model: the free base a 6-DOF joint to the world, the frame fixed.
    m = mbsa.from_mujoco(str(path))
    g = m.rigid(method="geometric")
    assert g["mobility"] == model.nv - rank
    # The MjModel itself (MuJoCo writes the XML it loaded last), and the XML text, give the
    # same mechanism.
    assert mbsa.from_mujoco(model).rigid(method="geometric")["mobility"] == g["mobility"]
    text = mbsa.from_mujoco(xml)
    assert text.mobility()["mobility"] == m.mobility()["mobility"]
