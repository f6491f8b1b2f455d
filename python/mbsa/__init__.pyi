"""Type stubs of mbsa (the Python package; docs/python.md)."""

import os
from typing import Any, Dict, Iterator, List, Mapping, Optional, Union

import numpy as np
import numpy.typing as npt

FORMAT_VERSION: int

class Error(Exception):
    """Base class of mbsa's errors."""

class InputError(Error):
    """An input mbsa cannot read or use, located as the command line shows it."""

    file: Optional[str]
    line: Optional[int]
    column: Optional[int]
    message: str
    help: Optional[str]
    rendered: str

class BudgetExceeded(Error):
    """An analysis would pass a limit of the budget (``max_work``)."""

class SolveError(Error):
    """A position solve did not converge."""

class Report(Dict[str, Any]):
    """The dict of a command's ``--format json`` output (docs/json.md)."""

    bodies: List[str]
    translations: npt.NDArray[np.float64]
    quaternions: npt.NDArray[np.float64]
    values: npt.NDArray[np.float64]
    joint_values: Dict[str, npt.NDArray[np.float64]]

class Placements:
    """Placements of the driven inputs, one dict each; ``summary`` holds the counts."""

    summary: Report
    def __iter__(self) -> Iterator[Report]: ...
    def __len__(self) -> int: ...

class Mechanism:
    """A mechanism: bodies, joints and driven inputs."""

    @property
    def name(self) -> str: ...
    @property
    def source(self) -> str: ...
    @property
    def bodies(self) -> List[str]: ...
    @property
    def joints(self) -> List[str]: ...
    def mobility(self, inputs: Optional[str] = None) -> Report: ...
    def analyze(
        self,
        geometry: str = "auto",
        inputs: Optional[str] = None,
        seed: int = 0,
        tolerance: Optional[float] = None,
        count_only: bool = False,
        exhaustive: bool = False,
        max_work: Optional[int] = None,
    ) -> Report: ...
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
    ) -> Report: ...
    def repair(self, candidates: int = 4, max_work: Optional[int] = None) -> Report: ...
    def repaired(
        self, candidate: int = 1, candidates: int = 4, max_work: Optional[int] = None
    ) -> Mechanism: ...
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
    ) -> Placements: ...
    def solve(
        self,
        set: Optional[Mapping[str, Any]] = None,
        inputs: Optional[str] = None,
        max_work: Optional[int] = None,
    ) -> Report: ...
    def sweep(
        self,
        joint: str,
        start: float,
        stop: float,
        step: float,
        set: Optional[Mapping[str, Any]] = None,
        inputs: Optional[str] = None,
        max_work: Optional[int] = None,
    ) -> Report: ...
    def dot(self, view: str = "diagram", inputs: Optional[str] = None) -> str: ...
    def to_toml(self) -> str: ...

def load(
    path_or_text: Union[str, "os.PathLike[str]"],
    format: Optional[str] = None,
    from_: Optional[str] = None,
    keyframe: Optional[str] = None,
    merge_pins: bool = False,
) -> Mechanism: ...
def examples() -> List[str]: ...
def from_pyrigi(framework: Any, name: str = "PyRigi framework") -> Mechanism: ...
def from_mujoco(model_or_path: Any, keyframe: Any = None) -> Mechanism: ...
