"""The compiled binding (python/src/lib.rs); the package's functions wrap it."""

from typing import Any, Callable, Dict, List, Optional, Tuple

__all__ = [
    "LaminaError",
    "__version__",
    "planarize",
    "read_mesh",
    "read_network",
    "run",
    "slice",
    "solid",
    "write_mesh",
    "write_network",
]
__version__: str

class LaminaError(ValueError): ...

def run(
    argv: List[str], progress: Optional[Callable[..., Any]] = None
) -> Tuple[bool, str, List[str]]: ...
# positions, edges, node radii, edge radii, normals (little-endian bytes) and meta (JSON text)
NetworkBytes = Tuple[bytes, bytes, bytes, bytes, bytes, str]

def planarize(
    argv: List[str], network: NetworkBytes, progress: Optional[Callable[..., Any]] = None
) -> Tuple[bool, str, str, str, bytes, bytes, List[str]]: ...
def solid(
    argv: List[str], network: NetworkBytes, progress: Optional[Callable[..., Any]] = None
) -> Tuple[str, bytes, bytes, List[str]]: ...
def slice(
    argv: List[str],
    models: List[Tuple[str, bytes, bytes]],
    progress: Optional[Callable[..., Any]] = None,
) -> Tuple[str, List[str]]: ...
def write_network(path: str, network: NetworkBytes) -> None: ...
def read_network(path: str) -> Dict[str, Any]: ...
def write_mesh(path: str, vertices: bytes, faces: bytes, colors: bytes) -> None: ...
def read_mesh(path: str) -> Tuple[bytes, bytes, Optional[bytes]]: ...
