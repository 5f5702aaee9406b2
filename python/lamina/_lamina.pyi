"""The compiled binding (python/src/lib.rs); the package's functions wrap it."""

from typing import Any, Callable, Dict, List, Optional, Tuple

__all__ = [
    "MAX_COORD",
    "__version__",
    "audit",
    "audit_file",
    "bifurcate",
    "buds",
    "cells",
    "lsystem",
    "nest",
    "option_names",
    "planarize",
    "plates",
    "print",
    "read_mesh",
    "read_network",
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
MAX_COORD: float

Callback = Optional[Callable[..., Any]]
# positions, edges, node radii, edge radii, normals (little-endian bytes) and meta (a dict)
NetworkBytes = Tuple[bytes, bytes, bytes, bytes, bytes, Any]
# vertices, faces, colours (little-endian bytes; colours may be empty)
MeshBytes = Tuple[bytes, bytes, bytes]
# positions, edges, axes, heights, reference, fixed normals, edge radii
AxesBytes = Tuple[bytes, bytes, bytes, bytes, bytes, bytes, bytes]

def venation(
    shape: str, outline: Optional[bytes], options: Dict[str, Any], progress: Callback = None
) -> Dict[str, Any]: ...
def venation_on_surface(
    mesh: MeshBytes, roots: List[Any], options: Dict[str, Any], progress: Callback = None
) -> Dict[str, Any]: ...
def veins(mesh: MeshBytes, options: Dict[str, Any], progress: Callback = None) -> Dict[str, Any]: ...
def lsystem(
    grammar: Optional[Tuple[str, str]],
    options: Dict[str, Any],
    derive_only: bool,
    progress: Callback = None,
) -> Dict[str, Any]: ...
def bifurcate(options: Dict[str, Any]) -> Dict[str, Any]: ...
def buds(
    program: str, name: str, options: Dict[str, Any], progress: Callback = None
) -> Dict[str, Any]: ...
def cells(
    network: NetworkBytes, surface: Optional[MeshBytes], options: Dict[str, Any]
) -> Dict[str, Any]: ...
def simplify(
    network: NetworkBytes, surface: Optional[MeshBytes], options: Dict[str, Any]
) -> Dict[str, Any]: ...
def planarize(
    network: NetworkBytes,
    surface: Optional[MeshBytes],
    options: Dict[str, Any],
    progress: Callback = None,
) -> Dict[str, Any]: ...
def audit(
    corners: bytes,
    counts: List[int],
    labels: Optional[Tuple[List[Optional[str]], List[Optional[str]], List[Optional[str]]]],
    options: Dict[str, Any],
) -> Dict[str, Any]: ...
def audit_file(path: str, options: Dict[str, Any]) -> Dict[str, Any]: ...
def size(axes: AxesBytes, options: Dict[str, Any], progress: Callback = None) -> Dict[str, Any]: ...
def plates(
    axes: AxesBytes,
    sizing: Optional[Tuple[bytes, bytes]],
    options: Dict[str, Any],
    out: Optional[str] = None,
) -> Dict[str, Any]: ...
def nest(
    plates: Any, options: Dict[str, Any], out: Optional[str] = None, progress: Callback = None
) -> Dict[str, Any]: ...
def solid(
    network: NetworkBytes, options: Dict[str, Any], progress: Callback = None
) -> Dict[str, Any]: ...
def slice(
    models: List[Tuple[str, bytes, bytes]], options: Dict[str, Any], progress: Callback = None
) -> Dict[str, Any]: ...
def print(
    network: NetworkBytes, options: Dict[str, Any], progress: Callback = None
) -> Dict[str, Any]: ...
def read_network(path: str, units: Optional[str] = None,
                 hatch_boundaries: bool = False) -> Dict[str, Any]: ...
def write_network(path: str, network: NetworkBytes) -> None: ...
def read_mesh(path: str) -> Dict[str, Any]: ...
def write_mesh(path: str, mesh: MeshBytes) -> None: ...
def option_names(function: str) -> List[str]: ...
