"""Interop: PyRigi bar-and-joint frameworks and MuJoCo models as mechanisms."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Sequence, Tuple

from . import Mechanism, load


def _num(x: Any) -> str:
    return repr(float(x))


def _bar_framework_toml(
    name: str, dim: int, points: Dict[Any, Sequence[float]], bars: List[Tuple[Any, Any]]
) -> str:
    if dim not in (2, 3):
        raise ValueError(f"a bar framework in dimension {dim}: mbsa models the plane and space")
    if not bars:
        raise ValueError("a framework without bars has no bodies")
    ids = {v: str(v).replace('"', "'") for v in points}
    body = {}
    for u, v in bars:
        body[(u, v)] = f"bar {ids[u]}-{ids[v]}"
    incident: Dict[Any, List[str]] = {v: [] for v in points}
    for (u, v), b in body.items():
        incident[u].append(b)
        incident[v].append(b)
    kind = "S" if dim == 3 else "R"
    space = "spatial" if dim == 3 else "planar"
    first = next(iter(body.values()))
    lines = [
        f'name = "{name}"',
        f'description = "bar-and-joint framework: {len(bars)} bars as bodies, '
        f'{kind} joints at the points"',
        f'space = "{space}"',
        f'frame = "{first}"',
        "",
    ]
    for v, bs in incident.items():
        if len(bs) < 2:
            continue  # an end point of one bar alone joins nothing
        p = [_num(c) for c in points[v]] + (["0"] if dim == 2 else [])
        quoted = ", ".join(f'"{b}"' for b in bs)
        lines += [
            "[[joint]]",
            f'id = "{ids[v]}"',
            f'type = "{kind}"',
            f"bodies = [{quoted}]",
            f"origin = [{', '.join(p)}]",
            "",
        ]
    return "\n".join(lines)


def from_pyrigi(framework: Any, name: str = "PyRigi framework") -> Mechanism:
    """A PyRigi ``Framework`` as a mechanism: every bar a body, every point a multiple joint
    of the bars that meet there (S joints in 3D, R joints in the plane, at the point's
    realization), the first bar the frame. In 3D each bar also spins about its own line (an
    isolated freedom, ``fully_isolated``) and the whole framework turns about the frame bar's
    line; in the plane the frame bar fixes every trivial motion. So the framework's nontrivial
    infinitesimal flexes number ``rigid()["geometric"]["mobility"]`` less the number of bars
    in 3D, and that mobility itself in the plane.
    """
    # `graph` and `dim` are properties in PyRigi 1.x, methods before.
    graph = framework.graph() if callable(framework.graph) else framework.graph
    dim = int(framework.dim() if callable(framework.dim) else framework.dim)
    realization = framework.realization(as_points=True, numerical=True)
    points = {v: [float(c) for c in realization[v]] for v in graph.nodes}
    bars = [(u, v) for u, v in graph.edges]
    return load(_bar_framework_toml(name, dim, points, bars), format="toml")


def from_mujoco(model_or_path: Any, keyframe: Any = None) -> Mechanism:
    """A MuJoCo model as a mechanism through mbsa's MJCF importer: a path to the XML, the
    XML text, or a ``mujoco.MjModel`` (then the XML of the model MuJoCo loaded last,
    ``mujoco.mj_saveLastXML``: load it from XML just before). ``keyframe`` (name or index)
    picks the configuration (default: qpos0)."""
    key = None if keyframe is None else str(keyframe)
    if isinstance(model_or_path, (str, os.PathLike)):
        text = os.fspath(model_or_path)
        if text.lstrip().startswith("<"):
            return load(text, from_="mjcf", keyframe=key)
        return load(os.fspath(model_or_path), from_="mjcf", keyframe=key)
    import tempfile

    import mujoco  # noqa: F401  (an MjModel was given)

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "model.xml")
        mujoco.mj_saveLastXML(path, model_or_path)
        return load(path, from_="mjcf", keyframe=key)
