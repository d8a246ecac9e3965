"""Type stubs of bvseg (the defaults, shown as ``...``, are the Rust core's: ``bvseg.DEFAULTS``)."""

import os
from typing import Any, Callable, Iterable, Mapping, Sequence, Union

import numpy as np
import numpy.typing as npt

from ._bvseg import GENERATOR as GENERATOR
from ._bvseg import MESH_EXTENSIONS as MESH_EXTENSIONS
from ._bvseg import Mesh as Mesh
from ._bvseg import MeshError as MeshError
from ._bvseg import RobotError as RobotError

__version__: str
DEFAULTS: Mapping[str, Any]
VERIFY_DEFAULTS: Mapping[str, Any]
TARGETS: tuple[str, ...]

class BvsegWarning(UserWarning): ...

# A path, a (vertices, faces) pair, an object with .vertices and .faces (trimesh), or a Mesh.
MeshLike = Union[str, os.PathLike[str], Mesh, Sequence[Any], Any]

def load_mesh(
    path: str | os.PathLike[str], *, object: str | None = None, mesh: str | None = None
) -> Mesh: ...

class Segmentation:
    def __init__(self, native: Any) -> None: ...
    @property
    def document(self) -> dict[str, Any]: ...
    @property
    def volumes(self) -> list[dict[str, Any]]: ...
    @property
    def metrics(self) -> dict[str, Any]: ...
    @property
    def history(self) -> list[dict[str, Any]]: ...
    @property
    def hierarchy(self) -> list[dict[str, Any]]: ...
    @property
    def schema(self) -> str: ...
    @property
    def k(self) -> int: ...
    @property
    def triangle_parts(self) -> npt.NDArray[np.uint32]: ...
    @property
    def sample_parts(self) -> npt.NDArray[np.uint32]: ...
    @property
    def labels(self) -> npt.NDArray[np.int64]: ...
    @property
    def tolerances_met(self) -> bool | None: ...
    @property
    def unmet(self) -> list[tuple[str, float, float]]: ...
    @property
    def budget_exhausted(self) -> bool: ...
    @property
    def seconds(self) -> float: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def mesh(self) -> Mesh: ...
    @property
    def params(self) -> dict[str, Any]: ...
    def to_json(self) -> str: ...
    def save(self, path: str | os.PathLike[str], *, with_mesh: bool = False) -> None: ...
    def save_labels(self, path: str | os.PathLike[str]) -> None: ...
    def summary(self) -> dict[str, Any]: ...

def segment(
    mesh: MeshLike,
    *,
    k: int | None = ...,
    tov: float | None = ...,
    max_protrusion: float | None = ...,
    max_protrusion_abs: float | None = ...,
    mov: float | None = ...,
    max_k: int | None = ...,
    kinds: str | Sequence[str] | None = ...,
    target: str | None = ...,
    max_hull_vertices: int | None = ...,
    samples: int | None = ...,
    seed: int | None = ...,
    threads: int | None = ...,
    merge: bool = ...,
    tighten: bool = ...,
    polish: bool = ...,
    hierarchy: bool = ...,
    margin: float | None = ...,
    timeout: float | None = ...,
    progress: Callable[[dict[str, Any]], object] | None = ...,
) -> Segmentation: ...
def verify(
    mesh: MeshLike,
    volumes: Segmentation | Iterable[Mapping[str, Any]] | Mapping[str, Any] | str | os.PathLike[str],
    *,
    points: int | None = ...,
    seed: int | None = ...,
    threads: int | None = ...,
) -> dict[str, Any]: ...

class Robot:
    name: str
    robot: str
    format: str
    out_dir: str
    urdf: str
    mjcf: str
    curobo: str
    files: list[str]
    links: list[dict[str, Any]]
    parts: int
    spheres: int
    seconds: float
    def __init__(self, d: dict[str, Any]) -> None: ...
    def link(self, name: str) -> dict[str, Any]: ...
    def volumes(self, link: str) -> list[dict[str, Any]]: ...

def robot(
    path: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    source: str = ...,
    max_parts: int | None = ...,
    total_parts: int | None = ...,
    spheres_per_link: int | None = ...,
    urdf_capsules: bool = ...,
    progress: Callable[[dict[str, Any]], object] | None = ...,
    **params: Any,
) -> Robot: ...
