"""Type stubs of the lamina package (see the module's docstring for the conventions)."""

import os
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__all__ = [
    "Cancelled",
    "LaminaError",
    "LaminaWarning",
    "__version__",
    "audit",
    "bifurcate",
    "buds",
    "cells",
    "lsystem",
    "nest",
    "planarize",
    "plates",
    "print",
    "read_mesh",
    "read_network",
    "rows",
    "simplify",
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
"""``progress(stage, message, done, total)``: ``total`` None when unknown; returning False
stops the stage."""

class LaminaError(ValueError):
    """A stage refused its input or options; the message names the argument."""

class LaminaWarning(UserWarning):
    """A note of a stage: a default it took, something it read but did not use."""

class Cancelled(KeyboardInterrupt):
    """The progress callback returned False."""

class Network(TypedDict, total=False):
    positions: npt.NDArray[np.float64]  # N×3
    edges: npt.NDArray[np.int64]  # E×2 node indices
    node_radius: npt.NDArray[np.float64]  # N
    edge_radius: npt.NDArray[np.float64]  # E
    normals: Optional[npt.NDArray[np.float64]]  # N×3 or None
    meta: Dict[str, Any]
    units: str
    notes: List[str]

class Mesh(TypedDict, total=False):
    vertices: npt.NDArray[np.float64]  # V×3
    faces: npt.NDArray[np.int64]  # F×3
    colors: Optional[npt.NDArray[np.float64]]  # V×3 in 0..1 or None
    units: str

MeshLike = Union[Mesh, Tuple[ArrayLike, ArrayLike], Tuple[ArrayLike, ArrayLike, ArrayLike]]
NetworkLike = Union[Network, ArrayLike]

class Grown(TypedDict):
    network: Network
    report: Dict[str, Any]
    notes: List[str]
    units: str

class Planarized(TypedDict):
    positions: npt.NDArray[np.float64]  # N×3
    edges: npt.NDArray[np.int64]  # E×2
    axes: npt.NDArray[np.float64]  # N×3 unit axes
    heights: npt.NDArray[np.float64]  # N
    reference: npt.NDArray[np.float64]  # N×3
    fixed_normals: npt.NDArray[np.float64]  # E×3, NaN rows for none
    edge_radius: npt.NDArray[np.float64]  # E
    panels: npt.NDArray[np.float64]  # P×4×3
    within: bool
    summary: Dict[str, Any]
    report: Dict[str, Any]
    notes: List[str]
    units: str

class Celled(TypedDict):
    mesh: Mesh
    normals: npt.NDArray[np.float64]
    table: Dict[str, Any]
    notes: List[str]
    units: str

class Audited(TypedDict):
    report: Dict[str, Any]
    within: bool
    notes: List[str]
    units: str

class Sized(TypedDict):
    sizing: Dict[str, Any]
    gauges: npt.NDArray[np.float64]  # per edge
    gauge_list: npt.NDArray[np.float64]
    within: bool
    notes: List[str]
    units: str

class Plated(TypedDict):
    plates: Dict[str, Any]
    welds: Dict[str, Any]
    assembly: Mesh
    files: List[str]
    within: bool
    notes: List[str]
    units: str

class Nested(TypedDict):
    nest: Dict[str, Any]
    bom: str
    svg: str
    outlines: Dict[str, npt.NDArray[np.float64]]
    nc: Dict[str, str]
    files: List[str]
    notes: List[str]
    units: str

class Solid(TypedDict):
    mesh: Mesh
    report: Dict[str, Any]
    notes: List[str]
    units: str

class Sliced(TypedDict):
    sl1: bytes
    report: Dict[str, Any]
    notes: List[str]
    units: str

def rows(table: Union[Dict[str, Any], List[Any]]) -> List[Dict[str, Any]]: ...
def read_network(path: PathLike, units: Optional[str] = None,
                 hatch_boundaries: bool = False) -> Network: ...
def write_network(path: PathLike, net: Network, units: Optional[str] = None) -> None: ...
def read_mesh(path: PathLike) -> Mesh: ...
def write_mesh(path: PathLike, mesh: MeshLike, units: Optional[str] = None) -> None: ...
def venation(
    *,
    shape: str = "ovate",
    mode: str = "closed",
    outline: Any = None,
    root: Any = None,
    seed: int = 1,
    units: Optional[str] = None,
    progress: Progress = None,
    **options: Any,
) -> Grown: ...
def venation_on_surface(
    vertices: Any,
    faces: Any = None,
    *,
    colors: Any = None,
    root: Any = None,
    seed: int = 1,
    units: Optional[str] = None,
    progress: Progress = None,
    **options: Any,
) -> Grown: ...
def veins(
    vertices: Any,
    faces: Any = None,
    *,
    sources: Any = None,
    root: Optional[int] = None,
    colors: Any = None,
    seed: int = 1,
    units: Optional[str] = None,
    progress: Progress = None,
    **options: Any,
) -> Grown: ...
def lsystem(
    *,
    axiom: Optional[str] = None,
    rules: Any = (),
    iterations: Optional[int] = None,
    grammar: Optional[PathLike] = None,
    derive_only: bool = False,
    seed: int = 1,
    units: Optional[str] = None,
    progress: Progress = None,
    **options: Any,
) -> Grown: ...
def bifurcate(*, seed: int = 1, units: Optional[str] = None, **options: Any) -> Grown: ...
def buds(program: str, *, progress: Progress = None, **options: Any) -> Solid: ...
def cells(
    positions: NetworkLike,
    edges: Optional[ArrayLike] = None,
    normals: Optional[ArrayLike] = None,
    *,
    surface: Optional[MeshLike] = None,
    units: Optional[str] = None,
    **options: Any,
) -> Celled: ...
def simplify(
    positions: NetworkLike,
    edges: Optional[ArrayLike] = None,
    *,
    surface: Optional[MeshLike] = None,
    units: Optional[str] = None,
    **options: Any,
) -> Grown: ...
def planarize(
    positions: NetworkLike,
    edges: Optional[ArrayLike] = None,
    normals: Optional[ArrayLike] = None,
    *,
    height: Optional[float] = None,
    tolerance: Optional[float] = None,
    method: str = "newton",
    surface: Optional[MeshLike] = None,
    node_radius: Optional[ArrayLike] = None,
    edge_radius: Optional[ArrayLike] = None,
    units: Optional[str] = None,
    progress: Progress = None,
    **options: Any,
) -> Planarized: ...
def audit(
    panels: Union[PathLike, Sequence[ArrayLike], Tuple[ArrayLike, Sequence[Sequence[int]]]],
    *,
    tolerance: Optional[float] = None,
    metric: str = "flatness",
    units: Optional[str] = None,
    **options: Any,
) -> Audited: ...
def size(
    axes: Union[Planarized, PathLike],
    *,
    support: Union[str, Sequence[str]] = (),
    load: Union[str, Sequence[str]] = (),
    progress: Progress = None,
    **options: Any,
) -> Sized: ...
def plates(
    axes: Union[Planarized, PathLike],
    *,
    sizing: Optional[Sized] = None,
    out: Optional[PathLike] = None,
    **options: Any,
) -> Plated: ...
def nest(
    plates: Union[Plated, Dict[str, Any], PathLike],
    *,
    sheet: Optional[str] = None,
    out: Optional[PathLike] = None,
    progress: Progress = None,
    **options: Any,
) -> Nested: ...
def solid(
    positions: NetworkLike,
    edges: Optional[ArrayLike] = None,
    node_radius: Optional[ArrayLike] = None,
    edge_radius: Optional[ArrayLike] = None,
    *,
    cell: Optional[float] = None,
    units: Optional[str] = None,
    progress: Progress = None,
    **options: Any,
) -> Solid: ...
def slice(
    models: Union[MeshLike, Sequence[MeshLike]],
    *,
    units: Optional[str] = None,
    progress: Progress = None,
    **options: Any,
) -> Sliced: ...
def print(
    positions: NetworkLike,
    edges: Optional[ArrayLike] = None,
    node_radius: Optional[ArrayLike] = None,
    edge_radius: Optional[ArrayLike] = None,
    *,
    units: Optional[str] = None,
    progress: Progress = None,
    **options: Any,
) -> Sliced: ...
