"""mbsa: structural analysis of multibody systems, from Python.

Read a mechanism with :func:`load` (a mechanism file, a bundled ``@name``, or a simulator
model: MJCF, SDFormat, URDF, OpenSim), then ask it for its mobility, structural groups, rigid
subsystems, input placements or positions. Every report is the dict the command line prints
with ``--format json`` (the same keys, docs/json.md), plus numpy arrays for poses.

>>> import mbsa
>>> mbsa.load("@rotor").analyze()["status"]
'determined'
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, Iterator, List, Mapping, Optional, Union

import numpy as np

from . import _mbsa
from ._mbsa import BudgetExceeded, Error, FORMAT_VERSION, InputError, SolveError

__all__ = [
    "load",
    "examples",
    "from_pyrigi",
    "from_mujoco",
    "Mechanism",
    "Report",
    "Placements",
    "Error",
    "InputError",
    "BudgetExceeded",
    "SolveError",
    "FORMAT_VERSION",
]


class Report(dict):
    """A report: the dict of the command's ``--format json`` output (``format_version``
    first). Solves and sweeps also carry numpy arrays as attributes (see :meth:`Mechanism.solve`
    and :meth:`Mechanism.sweep`)."""


def _parse(text: str) -> Report:
    return Report(json.loads(text))


def examples() -> List[str]:
    """The names of the bundled mechanisms (load one as ``mbsa.load("@name")``)."""
    return [name for name, _ in _mbsa.examples()]


def _looks_like_text(source: str) -> bool:
    head = source.lstrip()[:1]
    return "\n" in source or head in ("<", "{", "[")


def load(
    path_or_text: Union[str, "os.PathLike[str]"],
    format: Optional[str] = None,
    from_: Optional[str] = None,
    keyframe: Optional[str] = None,
    merge_pins: bool = False,
) -> "Mechanism":
    """Read a mechanism.

    ``path_or_text`` is a path (a ``str`` or ``os.PathLike``), ``"@name"`` for a bundled
    example, or the text of a file (a string with a newline, or one starting with ``<``,
    ``{`` or ``[``; errors name it ``<string>``). ``format`` forces ``"toml"``, ``"yaml"`` or
    ``"json"``; ``from_`` reads a simulator model as ``"mjcf"``, ``"sdf"``, ``"urdf"`` or
    ``"osim"`` (default: from the extension and the root element); ``keyframe`` picks an MJCF
    keyframe (name or index) as the configuration; ``merge_pins`` merges coincident coaxial
    revolute joints. Raises :class:`InputError` with ``file``, ``line`` and ``column``.
    """
    if isinstance(path_or_text, os.PathLike):
        source, is_path = os.fspath(path_or_text), True
    elif isinstance(path_or_text, str):
        source = path_or_text
        is_path = not source.startswith("@") and not _looks_like_text(source)
    else:
        raise TypeError("load() takes a path, '@name' or the text of a file")
    raw = _mbsa.load(source, is_path, format, from_, keyframe, merge_pins)
    return Mechanism(raw)


def _number(x: Union[float, str]) -> str:
    return x if isinstance(x, str) else repr(float(x))


def _sets(set: Optional[Mapping[str, Any]]) -> List[str]:
    out = []
    for joint, value in (set or {}).items():
        values = value if isinstance(value, (list, tuple, np.ndarray)) else [value]
        out.append(f"{joint}=" + ",".join(_number(v) for v in values))
    return out


def _pose_arrays(report: Report, poses: List[Dict[str, Any]]) -> None:
    report.bodies = [p["body"] for p in poses]
    report.translations = np.array([p["translation"] for p in poses], dtype=float).reshape(-1, 3)
    report.quaternions = np.array([p["quaternion"] for p in poses], dtype=float).reshape(-1, 4)


class Placements:
    """The placements of :meth:`Mechanism.transform`: iterate for one dict per placement
    (the lines of ``mbsa transform --format jsonl``); ``summary`` is the last line (counts and
    notes)."""

    def __init__(self, lines: List[str], summary: str) -> None:
        self._lines = lines
        self.summary: Report = _parse(summary)

    def __iter__(self) -> Iterator[Report]:
        return (_parse(line) for line in self._lines)

    def __len__(self) -> int:
        return len(self._lines)


class Mechanism:
    """A mechanism: bodies, joints and driven inputs. Made by :func:`load`,
    :func:`from_pyrigi` or :func:`from_mujoco`."""

    def __init__(self, raw: "_mbsa.RawMechanism") -> None:
        self._raw = raw

    @property
    def name(self) -> str:
        """The mechanism's ``name``."""
        return self._raw.name

    @property
    def source(self) -> str:
        """Where it was read from, as errors name it (a path, ``@name (file)``, ``<string>``)."""
        return self._raw.source

    @property
    def bodies(self) -> List[str]:
        """Body ids, the frame first."""
        return self._raw.bodies

    @property
    def joints(self) -> List[str]:
        """Joint ids."""
        return self._raw.joints

    def __repr__(self) -> str:
        return f"<mbsa.Mechanism {self.name!r}: {len(self.bodies)} bodies, {len(self.joints)} joints>"

    def mobility(self, inputs: Optional[str] = None) -> Report:
        """The Chebyshev–Grübler–Kutzbach count (``mbsa mobility --format json``)."""
        return _parse(self._raw.mobility_json(inputs))

    def analyze(
        self,
        geometry: str = "auto",
        inputs: Optional[str] = None,
        seed: int = 0,
        tolerance: Optional[float] = None,
        count_only: bool = False,
        exhaustive: bool = False,
        max_work: Optional[int] = None,
    ) -> Report:
        """Structural groups, solve levels, rank check and diagnosis (``mbsa analyze
        --format json``). ``geometry``: ``"auto"``, ``"file"`` or ``"random"``; ``inputs``
        replaces the driven inputs (``"1-2,1-13,13-15"``)."""
        return _parse(
            self._raw.analyze_json(inputs, geometry, seed, tolerance, count_only, exhaustive, max_work)
        )

    def rigid(
        self,
        method: str = "both",
        finite: bool = False,
        with_inputs: bool = False,
        geometry: str = "auto",
        seed: int = 0,
        tolerance: Optional[float] = None,
        inputs: Optional[str] = None,
        max_work: Optional[int] = None,
    ) -> Report:
        """Rigid subsystems (``mbsa rigid --format json``): ``method`` ``"both"``,
        ``"counting"`` (pebble game) or ``"geometric"`` (constraint Jacobian); ``finite`` adds
        the finite mobility at the file's configuration."""
        return _parse(
            self._raw.rigid_json(method, finite, with_inputs, geometry, seed, tolerance, inputs, max_work)
        )

    def repair(self, candidates: int = 4, max_work: Optional[int] = None) -> Report:
        """The joint changes that make the model simulate with its motion unchanged (``mbsa
        repair --format json``): ``before``, the checked ``candidates`` (best first) and
        ``notes``. docs/repair.md."""
        return _parse(self._raw.repair_json(candidates, max_work))

    def repaired(
        self, candidate: int = 1, candidates: int = 4, max_work: Optional[int] = None
    ) -> "Mechanism":
        """The model repaired by ``candidate`` (1 = the first listed), as a new
        :class:`Mechanism` (``mbsa repair --apply N``)."""
        return load(self._raw.repaired_toml(candidate, candidates, max_work), format="toml")

    def transform(
        self,
        limit: Optional[int] = None,
        rank: Optional[str] = None,
        on: Optional[str] = None,
        grounded: bool = False,
        keep: Optional[str] = None,
        exclude: Optional[str] = None,
        max_expansions: int = 64,
        count_only: bool = False,
        max_work: Optional[int] = None,
        base: str = "auto",
    ) -> Placements:
        """Every placement of the driven inputs that determines the mechanism (``mbsa
        transform --format jsonl``), at most ``limit`` count-valid ones examined per part.
        ``base``: ``"auto"`` drives a floating base (a free joint, its part's only joint to
        the frame) in full, ``"fixed"`` every free joint to the frame (``--fix-base``),
        ``"free"`` none (``--keep-free-base``); the summary's ``fixed_base`` names them."""
        lines, summary = self._raw.transform_jsonl(
            limit, rank, on, grounded, keep, exclude, max_expansions, count_only, max_work, base
        )
        return Placements(lines, summary)

    def solve(
        self,
        set: Optional[Mapping[str, Any]] = None,
        inputs: Optional[str] = None,
        max_work: Optional[int] = None,
    ) -> Report:
        """Every body's pose for the input values ``set`` (``{"O": 30}``: degrees, or
        ``"0.5rad"``; slides in file lengths), as ``mbsa solve --set O=30 --format json``.
        The report also has ``bodies``, ``translations`` (n×3) and ``quaternions`` (n×4,
        ``[w, x, y, z]``) as numpy arrays. Raises :class:`SolveError` when it does not
        converge."""
        r = _parse(self._raw.solve_json(_sets(set), inputs, max_work))
        _pose_arrays(r, r["poses"])
        return r

    def sweep(
        self,
        joint: str,
        start: float,
        stop: float,
        step: float,
        set: Optional[Mapping[str, Any]] = None,
        inputs: Optional[str] = None,
        max_work: Optional[int] = None,
    ) -> Report:
        """Step ``joint`` from ``start`` to ``stop`` by ``step`` (``mbsa solve --sweep
        JOINT=START..STOP:STEP --format json``), each step solved from the previous one;
        ``stopped`` says why it ended early (a dead point, a branch change). Arrays:
        ``values`` (steps), ``translations`` (steps×bodies×3), ``quaternions``
        (steps×bodies×4), ``joint_values`` (joint id → steps×k)."""
        spec = f"{joint}={_number(start)}..{_number(stop)}:{_number(step)}"
        r = _parse(self._raw.sweep_json(spec, _sets(set), inputs, max_work))
        steps = r["steps"]
        r.values = np.array([s["value"] for s in steps], dtype=float)
        r.bodies = [p["body"] for p in steps[0]["poses"]] if steps else self.bodies
        nb = len(r.bodies)
        r.translations = np.array(
            [[p["translation"] for p in s["poses"]] for s in steps], dtype=float
        ).reshape(len(steps), nb, 3)
        r.quaternions = np.array(
            [[p["quaternion"] for p in s["poses"]] for s in steps], dtype=float
        ).reshape(len(steps), nb, 4)
        ids = [jv["joint"] for jv in steps[0]["joint_values"]] if steps else []
        r.joint_values = {
            j: np.array([s["joint_values"][i]["values"] for s in steps], dtype=float)
            for i, j in enumerate(ids)
        }
        return r

    def dot(self, view: str = "diagram", inputs: Optional[str] = None) -> str:
        """Graphviz DOT text (``mbsa dot --view VIEW``): ``"diagram"`` (one node per
        structural group, one row per level), ``"structure"`` or ``"topology"``."""
        return self._raw.dot(view, inputs)

    def to_toml(self) -> str:
        """The mechanism as a format-v1 TOML file (docs/format.md)."""
        return self._raw.to_toml()


from ._interop import from_mujoco, from_pyrigi  # noqa: E402
