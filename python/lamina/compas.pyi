from typing import Any, Optional

from . import Mesh, Network

def to_network(network: Network) -> Any:
    """A ``compas.datastructures.Graph``."""

def from_network(graph: Any, units: Optional[str] = None) -> Network: ...
def to_mesh(mesh: Mesh) -> Any:
    """A ``compas.datastructures.Mesh``."""

def from_mesh(mesh: Any, units: Optional[str] = None) -> Mesh: ...
