"""Type stubs of the lamina package (see the module's docstring for the conventions)."""

import os
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__all__ = [
    "LaminaError",
    "LaminaWarning",
    "__version__",
    "audit",
    "cells",
    "command",
    "lsystem",
    "nest",
    "planarize",
    "plates",
    "read_mesh",
    "read_network",
    "size",
    "slice",
    "solid",
    "veins",
    "venation",
    "venation_on_surface",
    "write_mesh",
    "write_network",
]

__version__: str

PathLike = Union[str, "os.PathLike[str]"]
ArrayLike = npt.ArrayLike
Progress = Optional[Callable[[str, str, int, Optional[int]], Any]]
"""``progress(stage, message, done, total)``: ``total`` None for a spinner."""

class LaminaError(ValueError):
    """Bad input, a bad option or a failed write; the message is the binary's."""

class LaminaWarning(UserWarning):
    """A note of a command: a default it took, something it read but did not use."""

class Network(TypedDict):
    positions: npt.NDArray[np.float64]  # N×3, mm
    edges: npt.NDArray[np.int64]  # E×2 node indices
    node_radius: npt.NDArray[np.float64]  # N
    edge_radius: npt.NDArray[np.float64]  # E
    normals: Optional[npt.NDArray[np.float64]]  # N×3 or None
    meta: Dict[str, Any]

class Mesh(TypedDict):
    vertices: npt.NDArray[np.float64]  # V×3
    faces: npt.NDArray[np.int64]  # F×3
    colors: Optional[npt.NDArray[np.float64]]  # V×3 in 0..1 or None

MeshLike = Union[Mesh, Tuple[ArrayLike, ArrayLike], Tuple[ArrayLike, ArrayLike, ArrayLike]]
NetworkLike = Union[Network, ArrayLike]

class Grown(TypedDict):
    network: Network
    report: Dict[str, Any]
    report_json: str
    notes: List[str]

class Planarized(TypedDict):
    axes: npt.NDArray[np.float64]  # N×3 unit axes
    heights: npt.NDArray[np.float64]  # N
    panels: npt.NDArray[np.float64]  # P×4×3
    within: bool
    summary: Dict[str, Any]
    report: Dict[str, Any]
    report_json: str
    axes_json: str
    notes: List[str]

class Celled(TypedDict):
    mesh: Mesh
    normals: npt.NDArray[np.float64]
    table: Dict[str, Any]
    table_json: str
    notes: List[str]

class Audited(TypedDict):
    report: Dict[str, Any]
    report_json: str
    within: bool
    notes: List[str]

class Sized(TypedDict):
    sizing: Dict[str, Any]
    sizing_json: str
    within: bool
    notes: List[str]

class Plated(TypedDict):
    plates: Dict[str, Any]
    plates_json: str
    welds: Optional[Dict[str, Any]]
    assembly: Mesh
    files: Dict[str, bytes]
    within: bool
    notes: List[str]

class Nested(TypedDict):
    nest: Dict[str, Any]
    nest_json: str
    files: Dict[str, bytes]
    notes: List[str]

class Solid(TypedDict):
    mesh: Mesh
    report: Dict[str, Any]
    report_json: str
    notes: List[str]

class Sliced(TypedDict):
    sl1: bytes
    report: Dict[str, Any]
    report_json: str
    notes: List[str]

def command(*argv: Any, progress: Progress = ...) -> str:
    """Runs ``lamina ARGV…`` in-process on files; returns what it printed."""

def read_network(path: PathLike) -> Network: ...
def write_network(path: PathLike, network: Network) -> None: ...
def read_mesh(path: PathLike) -> Mesh: ...
def write_mesh(path: PathLike, mesh: MeshLike) -> None: ...
def venation(
    *,
    shape: str = "ovate",
    mode: str = "closed",
    outline: Union[ArrayLike, PathLike, None] = ...,
    root: Any = ...,
    seed: int = 1,
    progress: Progress = ...,
    **options: Any,
) -> Grown: ...
def venation_on_surface(
    vertices: ArrayLike,
    faces: ArrayLike,
    *,
    colors: Optional[ArrayLike] = ...,
    root: Any = ...,
    seed: int = 1,
    progress: Progress = ...,
    **options: Any,
) -> Grown: ...
def veins(
    vertices: ArrayLike,
    faces: ArrayLike,
    *,
    sources: Union[int, Sequence[int], None] = ...,
    root: Optional[int] = ...,
    colors: Optional[ArrayLike] = ...,
    seed: int = 1,
    progress: Progress = ...,
    **options: Any,
) -> Grown: ...
def lsystem(
    *,
    axiom: Optional[str] = ...,
    rules: Union[Sequence[str], Dict[str, str]] = ...,
    iterations: Optional[int] = ...,
    seed: int = 1,
    progress: Progress = ...,
    **options: Any,
) -> Grown: ...
def cells(
    positions: NetworkLike,
    edges: Optional[ArrayLike] = ...,
    normals: Optional[ArrayLike] = ...,
    *,
    surface: Optional[MeshLike] = ...,
    progress: Progress = ...,
    **options: Any,
) -> Celled: ...
def planarize(
    positions: NetworkLike,
    edges: Optional[ArrayLike] = ...,
    normals: Optional[ArrayLike] = ...,
    *,
    height: float = 100.0,
    tolerance: float = 0.01,
    method: str = "lbfgs",
    surface: Optional[MeshLike] = ...,
    node_radius: Optional[ArrayLike] = ...,
    edge_radius: Optional[ArrayLike] = ...,
    progress: Progress = ...,
    **options: Any,
) -> Planarized: ...
def audit(
    panels: Union[Sequence[ArrayLike], Tuple[ArrayLike, Sequence[Sequence[int]]], PathLike],
    *,
    tolerance: Optional[float] = ...,
    metric: str = "flatness",
    progress: Progress = ...,
    **options: Any,
) -> Audited: ...
def size(
    axes: Union[Planarized, Dict[str, Any], PathLike],
    *,
    support: Union[str, Sequence[str]] = ...,
    load: Union[str, Sequence[str]] = ...,
    progress: Progress = ...,
    **options: Any,
) -> Sized: ...
def plates(
    axes: Union[Planarized, Dict[str, Any], PathLike],
    *,
    sizing: Union[Sized, Dict[str, Any], PathLike, None] = ...,
    progress: Progress = ...,
    **options: Any,
) -> Plated: ...
def nest(
    plates: Union[Plated, Dict[str, Any], PathLike],
    *,
    sheet: Optional[str] = ...,
    progress: Progress = ...,
    **options: Any,
) -> Nested: ...
def solid(
    positions: NetworkLike,
    edges: Optional[ArrayLike] = ...,
    node_radius: Optional[ArrayLike] = ...,
    edge_radius: Optional[ArrayLike] = ...,
    *,
    cell: Optional[float] = ...,
    progress: Progress = ...,
    **options: Any,
) -> Solid: ...
def slice(
    models: Union[MeshLike, Sequence[MeshLike]], *, progress: Progress = ..., **options: Any
) -> Sliced: ...
