"""Collider names by engine preset (no bpy)."""

# Unreal's FBX importer: UBX_ box, USP_ sphere, UCP_ capsule, UCX_ convex (everything else:
# hulls, and ellipsoids and cylinders as convex meshes), then the render mesh's name.
UNREAL_PREFIX = {"obb": "UBX", "sphere": "USP", "capsule": "UCP"}

# Words of the plain preset.
PLAIN_KIND = {
    "obb": "box",
    "sphere": "sphere",
    "capsule": "capsule",
    "cylinder": "cylinder",
    "ellipsoid": "ellipsoid",
    "hull": "hull",
}

# Godot's scene importer: `-convcolonly` turns a mesh into a StaticBody3D with one
# ConvexPolygonShape3D of its vertices and drops the visible mesh. Every bvseg volume is convex,
# so this is the exact hint; `-colonly` would make a concave trimesh shape (static only, the
# slowest), and Godot's primitive hints exist only for Collada empties.
GODOT_SUFFIX = "-convcolonly"

PRESETS = ("UNREAL", "GODOT", "PLAIN")


def collider_name(preset, source, shape, index):
    """The name of the `index`-th collider (0-based) of `source` (the mesh's name)."""
    nn = f"{index:02d}"
    if preset == "UNREAL":
        return f"{UNREAL_PREFIX.get(shape, 'UCX')}_{source}_{nn}"
    if preset == "GODOT":
        return f"{source}_{nn}{GODOT_SUFFIX}"
    if preset == "PLAIN":
        return f"{source}_{PLAIN_KIND.get(shape, shape)}_{nn}"
    raise ValueError(f"unknown naming preset {preset!r}")
