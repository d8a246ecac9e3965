"""Collider meshes for bvseg's volumes, in plain Python (no bpy, so it can be tested alone).

Each volume of a `bvseg.volumes` file becomes a frame (a rotation and a centre in the space the
volumes were fitted in) and a convex mesh in that frame that ENCLOSES the volume: a box exactly,
the curved kinds with polyhedra whose every face lies on or outside the true surface (an
inscribed sphere mesh would cut into the mesh the volume encloses), a hull as its points.
The frame puts capsules and cylinders along local Z and boxes along their own axes, so that
Blender's rigid-body shapes, which it derives from the object's local bounds, match the volume.
"""

import math

# A UV sphere of this many segments and rings is scaled until its nearest face touches the
# unit sphere: 32 x 16 stands out by 1.0 % of the radius. The rings are even, so an equator
# ring splits it into the two caps of a capsule.
SPHERE_SEGMENTS = 32
SPHERE_RINGS = 16
# Ellipsoids become convex hulls: 12 x 6 is 62 vertices, within the 64 that PhysX cooks
# without simplifying (simplifying could cut in); it stands out by 6.9 % of each radius.
ELLIPSOID_SEGMENTS = 12
ELLIPSOID_RINGS = 6
# A cylinder's polygon circumscribes its circle: 32 sides stand out by 0.5 % at the corners.
CYLINDER_SEGMENTS = 32

# The Blender rigid-body collision shape of each volume kind (ellipsoids have none).
RIGID_BODY_SHAPES = {
    "obb": "BOX",
    "sphere": "SPHERE",
    "capsule": "CAPSULE",
    "cylinder": "CYLINDER",
    "ellipsoid": "CONVEX_HULL",
    "hull": "CONVEX_HULL",
}


class VolumeError(ValueError):
    """A volume of the file that is not one bvseg writes (unknown shape, missing field)."""


class Collider:
    """One volume as a mesh: `rotation` (3x3, rows) and `center` place the local frame in the
    fitting space; `vertices` are local; `faces` are outward vertex loops, or None for a hull,
    whose faces the caller computes from its points."""

    def __init__(self, shape, center, rotation, vertices, faces):
        self.shape = shape
        self.center = center
        self.rotation = rotation
        self.vertices = vertices
        self.faces = faces

    @property
    def rigid_body_shape(self):
        return RIGID_BODY_SHAPES[self.shape]

    def matrix(self):
        """The frame as a 4x4 row-major matrix (local to fitting space)."""
        r, c = self.rotation, self.center
        return [
            [r[0][0], r[0][1], r[0][2], c[0]],
            [r[1][0], r[1][1], r[1][2], c[1]],
            [r[2][0], r[2][1], r[2][2], c[2]],
            [0.0, 0.0, 0.0, 1.0],
        ]

    def world_vertices(self):
        """The vertices in the fitting space."""
        r, c = self.rotation, self.center
        return [
            tuple(c[i] + r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2] for i in range(3))
            for v in self.vertices
        ]


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _normalize(a):
    n = math.sqrt(_dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def uv_sphere(segments, rings):
    """The unit UV sphere (poles on Z): vertices on the sphere, outward faces (quads between
    rings, triangles at the poles). Vertex 0 is the north pole, the last the south pole, and
    ring j (1 .. rings-1) holds vertices 1 + (j-1)*segments ... ."""
    verts = [(0.0, 0.0, 1.0)]
    for j in range(1, rings):
        th = math.pi * j / rings
        for i in range(segments):
            ph = 2.0 * math.pi * i / segments
            verts.append((math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)))
    verts.append((0.0, 0.0, -1.0))
    return verts, _stitch(segments, rings - 1, len(verts) - 1)


def _stitch(segments, ring_count, south):
    """Outward faces of `ring_count` rings between vertex 0 (top) and `south` (bottom)."""
    faces = [(0, 1 + i, 1 + (i + 1) % segments) for i in range(segments)]
    for j in range(ring_count - 1):
        for i in range(segments):
            a = 1 + j * segments + i
            b = 1 + j * segments + (i + 1) % segments
            faces.append((a, a + segments, b + segments, b))
    base = 1 + (ring_count - 1) * segments
    faces += [(base + (i + 1) % segments, base + i, south) for i in range(segments)]
    return faces


def inradius(verts, faces):
    """The smallest distance from the origin to a face plane (faces planar, origin inside)."""
    best = math.inf
    for face in faces:
        a, b, c = (verts[k] for k in face[:3])
        n = _normalize(_cross(_sub(b, a), _sub(c, a)))
        best = min(best, abs(_dot(n, a)))
    return best


def enclosing_sphere(segments, rings):
    """A UV sphere scaled so that its nearest face plane touches the unit sphere: it encloses
    the unit sphere, and any affine image of it encloses the same image of the sphere."""
    verts, faces = uv_sphere(segments, rings)
    s = 1.0 / inradius(verts, faces)
    return [(x * s, y * s, z * s) for x, y, z in verts], faces


_SPHERE = enclosing_sphere(SPHERE_SEGMENTS, SPHERE_RINGS)
_ELLIPSOID = enclosing_sphere(ELLIPSOID_SEGMENTS, ELLIPSOID_RINGS)

IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def _frame_of_axes(axes):
    """A proper rotation (rows) whose columns are the axes rows; a left-handed set has its
    third axis flipped, which changes nothing for a box or an ellipsoid (both symmetric)."""
    u, v, w = (tuple(float(x) for x in a) for a in axes)
    if _dot(_cross(u, v), w) < 0.0:
        w = (-w[0], -w[1], -w[2])
    return ((u[0], v[0], w[0]), (u[1], v[1], w[1]), (u[2], v[2], w[2]))


def _frame_of_axis(axis):
    """A rotation (rows) that takes local Z to the unit vector `axis`."""
    a = _normalize(tuple(float(x) for x in axis))
    helper = (1.0, 0.0, 0.0) if abs(a[0]) < 0.9 else (0.0, 1.0, 0.0)
    u = _normalize(_cross(helper, a))
    v = _cross(a, u)
    return ((u[0], v[0], a[0]), (u[1], v[1], a[1]), (u[2], v[2], a[2]))


def box_mesh(half):
    """The box of half-extents `half` (8 vertices, 6 outward quads)."""
    hx, hy, hz = half
    verts = [(sx * hx, sy * hy, sz * hz) for sz in (-1, 1) for sy in (-1, 1) for sx in (-1, 1)]
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return verts, faces


def capsule_mesh(radius, half_length):
    """The enclosing sphere polyhedron of `radius`, its upper half moved up by `half_length`
    along Z and its lower half down, the equator ring in both: the polyhedron plus the segment
    (a Minkowski sum), which encloses the ball plus the segment, the capsule."""
    verts, _ = _SPHERE
    segs, rings = SPHERE_SEGMENTS, SPHERE_RINGS
    half = rings // 2
    top = [verts[0]] + verts[1 : 1 + half * segs]  # pole and rings 1 .. equator
    bottom = verts[1 + (half - 1) * segs :]  # equator .. rings-1 and the south pole
    out = [(x * radius, y * radius, z * radius + half_length) for x, y, z in top]
    out += [(x * radius, y * radius, z * radius - half_length) for x, y, z in bottom]
    # Rings 1 .. rings-1 with the equator twice: rings + 1 rings between the poles.
    return out, _stitch(segs, rings, len(out) - 1)


def cylinder_mesh(radius, half_length):
    """A prism whose polygon circumscribes the circle (its sides touch it), capped flat."""
    n = CYLINDER_SEGMENTS
    r = radius / math.cos(math.pi / n)
    ring = [(r * math.cos(2 * math.pi * i / n), r * math.sin(2 * math.pi * i / n)) for i in range(n)]
    verts = [(x, y, -half_length) for x, y in ring] + [(x, y, half_length) for x, y in ring]
    faces = [tuple(range(n - 1, -1, -1)), tuple(range(n, 2 * n))]
    faces += [(i, (i + 1) % n, n + (i + 1) % n, n + i) for i in range(n)]
    return verts, faces


def _bad(volume, key, what):
    return VolumeError(f"{volume.get('shape', '?')} volume: '{key}' must be {what}")


def _vec(volume, key):
    """Three finite numbers."""
    try:
        out = tuple(float(x) for x in volume[key])
    except (KeyError, TypeError, ValueError) as e:
        raise _bad(volume, key, "three numbers") from e
    if len(out) != 3 or not all(math.isfinite(x) for x in out):
        raise _bad(volume, key, "three finite numbers")
    return out


def _length(volume, key, allow_zero=False):
    """A finite positive number (or zero)."""
    try:
        x = float(volume[key])
    except (KeyError, TypeError, ValueError) as e:
        raise _bad(volume, key, "a number") from e
    if not math.isfinite(x) or x < 0.0 or (x == 0.0 and not allow_zero):
        raise _bad(volume, key, "positive")
    return x


def collider(volume):
    """The Collider of one volume of a `bvseg.volumes/1` or `/2` file (a dict). Raises
    VolumeError for a shape or field that the schemas do not have."""
    shape = volume.get("shape") if isinstance(volume, dict) else None
    if shape in ("obb", "ellipsoid"):
        center = _vec(volume, "center")
        try:
            axes = [tuple(float(x) for x in row) for row in volume["axes"]]
        except (KeyError, TypeError, ValueError) as e:
            raise _bad(volume, "axes", "three rows of three numbers") from e
        if len(axes) != 3 or any(len(a) != 3 or not all(map(math.isfinite, a)) for a in axes):
            raise _bad(volume, "axes", "three rows of three finite numbers")
        radii = _vec(volume, "radii")
        if min(radii) <= 0.0:
            raise _bad(volume, "radii", "positive")
        rotation = _frame_of_axes(axes)
        if shape == "obb":
            verts, faces = box_mesh(radii)
        else:
            unit, faces = _ELLIPSOID
            verts = [(x * radii[0], y * radii[1], z * radii[2]) for x, y, z in unit]
        return Collider(shape, center, rotation, verts, faces)
    if shape == "sphere":
        center = _vec(volume, "center")
        r = _length(volume, "radius")
        unit, faces = _SPHERE
        return Collider(shape, center, IDENTITY, [(x * r, y * r, z * r) for x, y, z in unit], faces)
    if shape in ("capsule", "cylinder"):
        center = _vec(volume, "center")
        rotation = _frame_of_axis(_vec(volume, "axis"))
        r = _length(volume, "radius")
        h = _length(volume, "half_length", allow_zero=shape == "capsule")
        verts, faces = capsule_mesh(r, h) if shape == "capsule" else cylinder_mesh(r, h)
        return Collider(shape, center, rotation, verts, faces)
    if shape == "hull":
        try:
            points = [tuple(float(x) for x in p) for p in volume["points"]]
        except (KeyError, TypeError, ValueError) as e:
            raise _bad(volume, "points", "a list of [x, y, z]") from e
        if len(points) < 4 or any(len(p) != 3 or not all(map(math.isfinite, p)) for p in points):
            raise _bad(volume, "points", "at least 4 finite [x, y, z]")
        n = len(points)
        center = tuple(sum(p[i] for p in points) / n for i in range(3))
        return Collider(shape, center, IDENTITY, [_sub(p, center) for p in points], None)
    raise VolumeError(f"unknown volume shape {shape!r}")
