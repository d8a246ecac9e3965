"""bvseg: wrap a 3D mesh in a tight union of ellipsoids, boxes, spheres, capsules, cylinders
and convex hulls.

The Python face of the Rust library: the same loader, algorithm, writers and checker as the
``bvseg`` command line, so that equal inputs give byte-identical files from either.

>>> import bvseg
>>> result = bvseg.segment("assets/meshes/bunny.obj", k=12)   # doctest: +SKIP
>>> result.volumes[0]["shape"], result.metrics["tov"]          # doctest: +SKIP
>>> result.save("bunny.json")                                  # doctest: +SKIP
>>> bvseg.verify("assets/meshes/bunny.obj", result)["enclosed"]  # doctest: +SKIP
True

Functions: :func:`segment`, :func:`verify`, :func:`load_mesh`, :func:`robot`. Errors: a bad
parameter is a ``ValueError`` naming it and its range (``TypeError`` for a value of the wrong
type); a bad mesh a :class:`MeshError` (a ``ValueError``); a bad robot file a
:class:`RobotError` (a ``ValueError``); a missing file a ``FileNotFoundError``; a run past its
``timeout`` a ``TimeoutError``. Warnings about a mesh (welded vertices, holes, ...)
are issued as :class:`BvsegWarning`. The manual: python/README.md in the repository.
"""

from __future__ import annotations

import json
import os
import types
import warnings as _warnings
from typing import Any, Callable, Iterable, Mapping, Sequence, Union

import numpy as np

from . import _bvseg
from ._bvseg import GENERATOR, MESH_EXTENSIONS, Mesh, MeshError, RobotError

__version__ = "0.1.0"

__all__ = [
    "BvsegWarning",
    "DEFAULTS",
    "GENERATOR",
    "MESH_EXTENSIONS",
    "Mesh",
    "MeshError",
    "Robot",
    "RobotError",
    "Segmentation",
    "TARGETS",
    "VERIFY_DEFAULTS",
    "load_mesh",
    "robot",
    "segment",
    "verify",
]

#: The defaults of :func:`segment`'s keyword arguments, read from the Rust core's
#: ``Params::default()`` (``None``: off, or chosen at run time).
DEFAULTS: Mapping[str, Any] = types.MappingProxyType(dict(_bvseg.defaults()))

#: The defaults of :func:`verify`'s options (``bvseg_verify::VerifyOptions::default()``).
VERIFY_DEFAULTS: Mapping[str, Any] = types.MappingProxyType(dict(_bvseg.verify_defaults()))

#: The engine names ``target=`` takes; each also as ``NAME-hull`` (with convex hulls), and
#: ``rapier``, ``avian`` (parry) and ``isaac`` (physx).
TARGETS: tuple[str, ...] = tuple(_bvseg.targets())

# The largest volumes document read, as the command line's reader.
_MAX_VOLUMES_BYTES: int = _bvseg.MAX_VOLUMES_BYTES


class BvsegWarning(UserWarning):
    """What the command line prints as a warning: what loading changed or found (welded
    vertices, dropped degenerate triangles, holes, pieces, ...) and runs cut short by their
    bound on work. The same lines are in :attr:`Mesh.warnings` and
    :attr:`Segmentation.warnings`."""


MeshLike = Union[str, "os.PathLike[str]", Mesh, Sequence[Any], Any]


def load_mesh(path: str | os.PathLike[str], *, object: str | None = None, mesh: str | None = None) -> Mesh:
    """Load a mesh file (``.obj``, ``.gltf``, ``.glb``, ``.stl``) as ``bvseg segment`` does:
    every object merged, exactly coincident positions welded, degenerate triangles dropped, an
    inward-facing surface turned outward.

    ``object`` selects one OBJ object or group, ``mesh`` the glTF nodes of one mesh (the
    command line's ``--object`` and ``--mesh``).

    Returns a :class:`Mesh`: ``.vertices`` (float64, n x 3), ``.faces`` (int64, m x 3),
    ``.warnings``, ``.stats``, ``.report``, ``.dropped``; ``vertices, faces = mesh`` unpacks it.

    Raises ``FileNotFoundError`` (and other ``OSError``) when the file cannot be read, and
    :class:`MeshError` when it is not a mesh bvseg can use.
    """
    return _bvseg.load_mesh(os.fspath(path), object=object, mesh=mesh)


def _array(x: Any, kind: str, name: str, what: str) -> np.ndarray:
    """``x`` as a C-contiguous (n, 3) array of float64 (``kind`` "f") or int64 ("i")."""
    try:
        a = np.asarray(x)
    except Exception as e:  # noqa: BLE001 - any failure to make an array is a bad mesh
        raise MeshError(f"{name}: {what} cannot be read as an array: {e}") from None
    if a.size == 0:
        a = a.reshape(0, 3)
    if a.ndim != 2 or a.shape[1] != 3:
        rows = "triangles" if what == "faces" else "vertices"
        raise MeshError(f"{name}: {what} must have shape (n, 3) ({rows}), got {a.shape}")
    if kind == "f":
        if a.dtype.kind not in "fiub":
            raise MeshError(f"{name}: {what} must be numbers, got dtype {a.dtype}")
        return np.ascontiguousarray(a, dtype=np.float64)
    if a.dtype.kind == "f":
        if not (np.isfinite(a).all() and (a == np.floor(a)).all()):
            raise MeshError(f"{name}: {what} must be integer vertex indices, got non-integral floats")
    elif a.dtype.kind not in "iub":
        raise MeshError(f"{name}: {what} must be integer vertex indices, got dtype {a.dtype}")
    if a.dtype.kind == "u" and a.size and int(a.max()) > np.iinfo(np.int64).max:
        raise MeshError(f"{name}: {what}: vertex index {int(a.max())} is out of range")
    return np.ascontiguousarray(a, dtype=np.int64)


def _as_mesh(mesh: MeshLike, name: str | None = None) -> Mesh:
    """Any mesh input :func:`segment` takes, as a :class:`Mesh`."""
    if isinstance(mesh, Mesh):
        return mesh
    if isinstance(mesh, (str, os.PathLike)):
        return load_mesh(mesh)
    if isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        vertices, faces = mesh
        name = name or "arrays"
    elif hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        vertices, faces = mesh.vertices, mesh.faces
        name = name or f"<{type(mesh).__module__}.{type(mesh).__qualname__}>"
    else:
        raise TypeError(
            "mesh must be a path, a (vertices, faces) pair of arrays, or an object with "
            f".vertices and .faces (such as a trimesh.Trimesh), got {type(mesh).__name__}"
        )
    v = _array(vertices, "f", name, "vertices")
    f = _array(faces, "i", name, "faces")
    return _bvseg.mesh_from_arrays(v, f, name)


class Segmentation:
    """The result of :func:`segment`.

    The figures and volumes come from the ``bvseg.volumes`` document (:meth:`to_json`), parsed
    once: :attr:`volumes`, :attr:`metrics`, :attr:`history`, :attr:`hierarchy` are exactly its
    lists and objects. Per-triangle and per-sample parts are numpy arrays.
    """

    __slots__ = ("_native", "_doc")

    def __init__(self, native: _bvseg.NativeSegmentation) -> None:
        self._native = native
        self._doc: dict[str, Any] | None = None

    @property
    def document(self) -> dict[str, Any]:
        """The ``bvseg.volumes/1`` or ``/2`` document as a dict (``json.loads(to_json())``)."""
        if self._doc is None:
            self._doc = json.loads(self._native.to_json())
        return self._doc

    @property
    def volumes(self) -> list[dict[str, Any]]:
        """One dict per part, as the JSON file's ``volumes``: ``shape``, the shape's fields
        (``center``, ``axes`` as rows and ``radii``; ``radius``; ``axis``, ``half_length``;
        ``points`` for hulls), ``fraction`` and ``protrusion``."""
        return self.document["volumes"]

    @property
    def metrics(self) -> dict[str, Any]:
        """The file's ``metrics``: k, tov, mov, protrusion, protrusion_rel, diagonal, samples, f."""
        return self.document["metrics"]

    @property
    def history(self) -> list[dict[str, Any]]:
        """Every refinement step, as the file's ``history``: step, k, f, tov, mov, protrusion."""
        return self.document["history"]

    @property
    def hierarchy(self) -> list[dict[str, Any]]:
        """The bounding-volume hierarchy over the parts, as the file's ``hierarchy``."""
        return self.document["hierarchy"]

    @property
    def schema(self) -> str:
        """``bvseg.volumes/1`` (ellipsoids and boxes only) or ``bvseg.volumes/2``."""
        return self.document["schema"]

    @property
    def k(self) -> int:
        """The number of parts."""
        return self._native.k

    @property
    def bones(self) -> list[dict[str, Any] | None]:
        """For each part, the bone its volume moves with (a skinned glTF character, or a mesh
        given a skeleton): a dict with ``joint`` (index into the skeleton), ``name``, ``node``
        (the glTF node index, or None) and ``parent`` (the parent joint's index, or None); None
        for every part of a mesh without a skeleton. The volumes' ``bone`` field names the
        same joint."""
        return self._native.bones

    @property
    def triangle_parts(self) -> np.ndarray:
        """uint32, per triangle of :attr:`mesh` (welded, degenerate ones dropped): the part whose
        volume encloses it."""
        return self._native.triangle_parts

    @property
    def sample_parts(self) -> np.ndarray:
        """uint32, per interior sample: its part."""
        return self._native.sample_parts

    @property
    def labels(self) -> np.ndarray:
        """int64, per triangle given (a file's, after fanning polygons; or the faces array): its
        part, or -1 for a triangle dropped as degenerate (what :meth:`save_labels` writes)."""
        return self._native.labels

    @property
    def tolerances_met(self) -> bool | None:
        """Whether a tolerance-mode run met its tolerances; ``None`` with a fixed ``k``."""
        return self._native.tolerances_met

    @property
    def unmet(self) -> list[tuple[str, float, float]]:
        """The tolerances left unmet: ``(name, value, tolerance)``, name ``"tov"``,
        ``"protrusion"`` (mesh units) or ``"mov"``."""
        return self._native.unmet

    @property
    def budget_exhausted(self) -> bool:
        """Whether the run's bound on work cut refinement short (the volumes still enclose)."""
        return self._native.budget_exhausted

    @property
    def seconds(self) -> float:
        """Wall time of the run."""
        return self._native.seconds

    @property
    def warnings(self) -> list[str]:
        """The mesh's warnings and the run's, one line each (issued as :class:`BvsegWarning`)."""
        return self._native.warnings

    @property
    def mesh(self) -> Mesh:
        """The mesh that was segmented."""
        return self._native.mesh

    @property
    def params(self) -> dict[str, Any]:
        """The parameters of the run, defaults filled in."""
        return self._native.params

    def to_json(self) -> str:
        """The ``bvseg.volumes`` document, the very string ``bvseg segment -o FILE.json`` writes."""
        return self._native.to_json()

    def save(self, path: str | os.PathLike[str], *, with_mesh: bool = False) -> None:
        """Write the volumes to ``path`` in the format its extension names: ``.json`` (the
        ``bvseg.volumes`` document), ``.glb`` (glTF 2.0 with physics colliders), ``.xml``
        (MuJoCo MJCF), ``.obj`` (proxy meshes); atomically, byte-identical to what
        ``bvseg segment -o PATH`` writes for the same mesh and parameters. ``with_mesh``
        (``.glb`` only) also writes the mesh, coloured by part (``--with-mesh``).

        Raises ``ValueError`` for an unknown extension, ``OSError`` when the file cannot be
        written (a missing directory is a ``FileNotFoundError``)."""
        self._native.save(os.fspath(path), with_mesh=with_mesh)

    def save_labels(self, path: str | os.PathLike[str]) -> None:
        """Write :attr:`labels`, one per line (``bvseg segment --labels PATH``)."""
        self._native.save_labels(os.fspath(path))

    def summary(self) -> dict[str, Any]:
        """What ``bvseg segment --json`` prints: k, tov, mov, f, protrusion, protrusion_rel,
        mesh, samples, kind, triangles, tolerances, tolerances_met, seconds, outputs (empty
        here), warnings."""
        return json.loads(self._native.summary_json())

    def __repr__(self) -> str:
        m = self.metrics
        return (
            f"<bvseg.Segmentation of {self.mesh.name!r}: k={self.k}, TOV={m['tov']:.4f}, "
            f"protrusion={m['protrusion_rel']:.4f} of the diagonal>"
        )


def segment(
    mesh: MeshLike,
    *,
    progress: Callable[[dict[str, Any]], object] | None = None,
    **params: Any,
) -> Segmentation:
    # The docstring is below, filled in with the core's defaults.
    m = _as_mesh(mesh)
    native = _bvseg.segment(m, progress=progress, **params)
    for w in native.warnings:
        _warnings.warn(f"{m.name}: {w}", BvsegWarning, stacklevel=2)
    return Segmentation(native)


segment.__doc__ = f"""Segment ``mesh`` and bound each part, as ``bvseg segment`` does.

``mesh``: a path (any format :func:`load_mesh` reads), a ``(vertices, faces)`` pair of
arrays (n x 3 numbers, m x 3 vertex indices), any object with ``.vertices`` and ``.faces``
(a ``trimesh.Trimesh``), or a :class:`Mesh`. Arrays take the loader's own last step, so the
same mesh gives the same result, from a file or from its arrays.

Keyword arguments (the command line's options; the defaults are the core's):

- ``k`` (default {DEFAULTS['k']}: tolerance mode): exactly this many parts (``--k``); cannot
  be combined with the tolerances.
- ``tov`` ({DEFAULTS['tov']}): tolerance on the total outside volume TOV.
- ``max_protrusion`` ({DEFAULTS['max_protrusion']}): tolerance on the protrusion, a fraction
  of the bounding-box diagonal; or ``max_protrusion_abs`` in mesh units.
- ``mov`` ({DEFAULTS['mov']}: unchecked): tolerance on the largest per-part outside volume.
- ``max_k`` ({DEFAULTS['max_k']}): most parts the tolerance loop may reach.
- ``kinds`` ({DEFAULTS['kinds']!r}): the kinds of volume, a comma list (``"capsule"``,
  ``"obb,capsule,sphere"``, ``"mixed"``, ``"all"``) or a list of names (``--bv``); or
  ``target``: an engine's native set, one of {", ".join(TARGETS)} (``-hull`` adds hulls).
- ``max_hull_vertices`` ({DEFAULTS['max_hull_vertices']}): most vertices of a hull.
- ``samples`` ({DEFAULTS['samples']}): target number of interior samples.
- ``seed`` ({DEFAULTS['seed']}): seed of the initialisation with ``k`` (the tolerance mode does not use it); equal seeds, equal results.
- ``threads`` (all cores): worker threads (a pool of its own); the result does not depend on it.
- ``merge`` ({DEFAULTS['merge']}), ``tighten`` ({DEFAULTS['tighten']}): ``False`` is
  ``--no-merge``, ``--no-tighten`` (``polish``, the former name of ``tighten``, is read as it).
- ``margin`` ({DEFAULTS['margin']}): grow every volume outward by this, in mesh units.
- ``skeleton`` ({DEFAULTS['skeleton']!r}): where the first parts are seeded from: ``"rig"``
  (the mesh's own skeleton, a skinned file's; ``"skin"``, its former name, is read as it),
  ``"auto"`` (an approximate curve skeleton) or ``"none"``.
- ``sampling`` ({DEFAULTS['sampling']!r}): ``"regular"`` or ``"adaptive"`` (a finer lattice whose
  thick inside is gathered into weighted blocks; ``--sampling``).
- ``route`` ({DEFAULTS['route']!r}): ``"auto"``, ``"lattice"`` (partition the sampled interior:
  the paper's method) or ``"surface"`` (clusters of triangles: open, thin or many-piece meshes
  and skinned characters; ``--route``, docs/method.md "Two routes").
- ``per_bone`` (3): most volumes per bone of a skinned character on the surface route; 1 is a
  ragdoll, one volume per bone that moves triangles.
- ``hierarchy`` ({DEFAULTS['hierarchy']}): build the bounding-volume hierarchy over the parts
  (about a sixth of a default run); only :meth:`Segmentation.to_json` carries it, so
  ``False`` suits a run written to GLB, MJCF or OBJ alone (its JSON then has an empty one).
- ``timeout`` (none): give up after this many seconds with ``TimeoutError``.
- ``progress``: called with a dict per refinement step (the keys of the file's ``history``:
  step, k, f, tov, mov, protrusion), with the GIL held; if it raises, the run is cancelled and
  the exception propagates.

The GIL is released during the run (taken back briefly after each step, for ``progress`` and
Ctrl-C). Returns a :class:`Segmentation`.

Raises ``ValueError`` for a parameter out of its range (the core's message names it and the
range), ``TypeError`` for a value of the wrong type or an unknown keyword, :class:`MeshError`
for a mesh that cannot be segmented (including one that encloses no volume), ``OSError`` for a
file that cannot be read, ``TimeoutError`` past ``timeout``.
"""


def _volumes_text(volumes: Any) -> tuple[str, str]:
    """The volumes document :func:`verify` takes, as text, and what messages call it."""
    if isinstance(volumes, Segmentation):
        return volumes.to_json(), "<segmentation>"
    if isinstance(volumes, str) and volumes.lstrip().startswith("{"):
        return volumes, "<json>"
    if isinstance(volumes, (str, os.PathLike)):
        path = os.fspath(volumes)
        if os.path.getsize(path) > _MAX_VOLUMES_BYTES:
            raise ValueError(f"{path}: the file is larger than {_MAX_VOLUMES_BYTES} bytes; refusing to load it")
        with open(path, "rb") as f:
            data = f.read()
        try:
            return data.decode("utf-8"), path
        except UnicodeDecodeError as e:
            raise ValueError(f"{path}: not valid JSON: not UTF-8 ({e})") from None
    if isinstance(volumes, Mapping):
        return json.dumps(volumes), "<dict>"
    if isinstance(volumes, Iterable):
        vols = list(volumes)
        v1 = all(isinstance(v, Mapping) and v.get("shape") in ("ellipsoid", "obb") for v in vols)
        doc = {"schema": "bvseg.volumes/1" if v1 else "bvseg.volumes/2", "kind": "mixed", "volumes": vols}
        return json.dumps(doc), "<volumes>"
    raise TypeError(
        "volumes must be a Segmentation, a list of volume dicts, a bvseg.volumes document "
        f"(dict or JSON string) or the path of one, got {type(volumes).__name__}"
    )


def verify(
    mesh: MeshLike,
    volumes: Any,
    *,
    points: int | None = None,
    seed: int | None = None,
    threads: int | None = None,
) -> dict[str, Any]:
    """Check ``volumes`` against ``mesh`` independently, as ``bvseg verify`` does (the
    ``bvseg-verify`` crate, which shares no code with the segmentation): is every triangle
    inside the union of the volumes, and how far do they stick out?

    ``mesh``: as :func:`segment` takes it. ``volumes``: a :class:`Segmentation`, a list of
    volume dicts (as :attr:`Segmentation.volumes`, each with its ``fraction``), a
    ``bvseg.volumes`` document as a dict or a JSON string, or the path of a volumes file.
    ``points`` (default {points}) grid points measure the outside volumes, jittered by
    ``seed`` (0); ``threads`` (all cores) does not change the report.

    Returns the report ``bvseg verify --json`` prints, as a dict: ``enclosed`` (every triangle
    inside), ``triangles_unenclosed``, ``max_escape_rel`` and ``worst_triangle`` (the largest
    escape, over the diagonal), ``tov`` and ``tov_se``, ``mov``, ``ov``, ``protrusion`` and
    ``protrusion_rel``, ``closed``, ``vol_mesh``, ``coverage_interior``, the ``reported_*``
    figures of the document, ...

    Raises ``ValueError`` for a document that breaks the schema or options out of range,
    :class:`MeshError` for a bad mesh.
    """
    m = _as_mesh(mesh)
    text, name = _volumes_text(volumes)
    options = {k: v for k, v in (("points", points), ("seed", seed), ("threads", threads)) if v is not None}
    return json.loads(_bvseg.verify(m, text, name, **options))


verify.__doc__ = (verify.__doc__ or "").replace("{points}", f"{VERIFY_DEFAULTS['points']:,}")


class Robot:
    """The result of :func:`robot`: what was written and what each link got.

    Attributes: ``name`` (the outputs' file stem), ``robot`` (the model's name in the file),
    ``format`` (``"urdf"`` or ``"mjcf"``), ``out_dir``, ``urdf``, ``mjcf``, ``curobo`` and
    ``manifest`` (the paths of ``<name>.urdf``, ``<name>.xml``, ``curobo.yml`` and
    ``manifest.json``), ``files`` (every path written, ``manifest.json`` last), ``parts`` and
    ``spheres`` (over all links), ``warnings`` (what was left as it was and why, one line
    each: a mesh of a format bvseg cannot read, a link whose meshes enclose no volume),
    ``seconds``, and ``links``: one dict per link of the file, in file order (an MJCF's world
    body first, as ``world``), with ``name``, ``meshes`` (mesh geoms or collisions
    segmented), ``triangles``, ``parts``, ``shapes`` (each part's kind), ``kept`` (the MJCF's
    own primitive colliders, kept), ``spheres`` (in curobo.yml), ``tolerances_met`` and
    ``volumes`` (the path of its ``bvseg.volumes`` document, None for a link not segmented).
    """

    __slots__ = ("_d",)

    def __init__(self, d: dict[str, Any]) -> None:
        self._d = d

    def __getattr__(self, name: str) -> Any:
        try:
            return self._d[name]
        except KeyError:
            raise AttributeError(name) from None

    def link(self, name: str) -> dict[str, Any]:
        """The dict of the link called ``name`` (``KeyError`` if there is none)."""
        for link in self._d["links"]:
            if link["name"] == name:
                return link
        raise KeyError(name)

    def volumes(self, link: str) -> list[dict[str, Any]]:
        """The volumes of link ``link``, as its ``bvseg.volumes`` document lists them (in the
        link's frame); ``[]`` for a link without meshes."""
        path = self.link(link)["volumes"]
        if path is None:
            return []
        with open(path, encoding="utf-8") as f:
            return json.load(f)["volumes"]

    def __repr__(self) -> str:
        segmented = sum(1 for link in self._d["links"] if link["volumes"] is not None)
        return (
            f"<bvseg.Robot {self._d['name']!r}: {segmented} links segmented, {self._d['parts']} parts, "
            f"{self._d['spheres']} spheres in {self._d['out_dir']!r}>"
        )


def robot(
    path: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    source: str = "collision",
    max_parts: int | None = None,
    total_parts: int | None = None,
    spheres_per_link: int | None = None,
    urdf_capsules: bool = False,
    progress: Callable[[dict[str, Any]], object] | None = None,
    **params: Any,
) -> Robot:
    # The docstring is below, filled in with the defaults.
    result = Robot(
        _bvseg.robot(
            os.fspath(path),
            os.fspath(out_dir),
            source=source,
            max_parts=max_parts,
            total_parts=total_parts,
            spheres_per_link=spheres_per_link,
            urdf_capsules=urdf_capsules,
            progress=progress,
            **params,
        )
    )
    for w in result.warnings:
        _warnings.warn(w, BvsegWarning, stacklevel=2)
    return result


robot.__doc__ = f"""Segment every link of a robot and write it with primitive colliders, as
``bvseg robot PATH -o OUT_DIR`` does (the same run, the same files).

``path``: a URDF (``.urdf``) or MJCF (``.xml``) file. Each link's collision meshes
(``source="visual"``: its visual ones) are segmented in the link's frame, and ``out_dir``
(created if missing) gets ``<name>.urdf`` and ``<name>.xml``: the input file as it was but
for its collision meshes, replaced by boxes, spheres and cylinders (capsules with
``urdf_capsules``) in the same links, and the other format made from its links; an MJCF's
included files beside it; ``curobo.yml`` (cuRobo's ``collision_spheres`` and
``self_collision_ignore``), ``links/<link>.json``, and ``manifest.json``, written last.

Budgets: ``max_parts`` per link (default {_bvseg.DEFAULT_PARTS_PER_LINK}), or ``total_parts``
for the whole robot shared among the links by volume (each at least one);
``spheres_per_link`` (default
{_bvseg.DEFAULT_SPHERES_PER_LINK}) spheres per link in curobo.yml. The other keyword arguments
are :func:`segment`'s (``samples``, ``tov``, ``max_protrusion``, ``kinds``, ``target``,
``k``, ``threads``, ``timeout`` for the whole robot, ...), applied to each link; the kinds
are narrowed to those URDF has (box, sphere, cylinder, and capsule with ``urdf_capsules``).
``progress`` is called with a dict per refinement step: :func:`segment`'s keys, and ``link``
and ``spheres`` (whether it is the run for curobo.yml).

Returns a :class:`Robot`. Raises :class:`RobotError` for a robot file that cannot be used
(not XML, not a robot, a link name used twice, a joint whose parent or child is not a link,
an include cycle), ``FileNotFoundError`` for a robot or mesh file that is not there,
:class:`MeshError` for a link's mesh that cannot be read (the message names the link and the
file), ``ValueError``/``TypeError`` for bad arguments, ``TimeoutError`` past ``timeout``.
Nothing is written unless every link was segmented. A mesh bvseg cannot replace (a format it
does not read, meshes that enclose no volume) stays in the output as it was and is named in
``warnings``, which are also issued as :class:`BvsegWarning`.
"""
