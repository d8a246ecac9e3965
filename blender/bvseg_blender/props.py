"""The run's settings: the operator's properties, and the same on the scene for the panel."""

from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

# The CLI's --target names (and `primitives`, its default set, and `custom`, a --bv list).
TARGETS = [
    (
        "primitives",
        "Primitives",
        "Ellipsoid, box, sphere, capsule, cylinder: bvseg's default set, the tightest "
        "without hulls (ellipsoids become convex meshes)",
    ),
    (
        "physx",
        "PhysX, Unreal, Isaac",
        "Box, sphere, capsule, cylinder (--target physx; Unreal has no cylinder: it gets a convex mesh)",
    ),
    (
        "physx-hull",
        "PhysX, Unreal, Isaac + hulls",
        "Box, sphere, capsule, cylinder, convex hull (--target physx-hull)",
    ),
    ("gltf", "glTF physics", "Box, sphere, capsule, cylinder (--target gltf)"),
    ("gltf-hull", "glTF physics + hulls", "Box, sphere, capsule, cylinder, convex hull (--target gltf-hull)"),
    ("parry", "Godot, Jolt, Unity, rapier, Avian", "Box, sphere, capsule, cylinder (--target parry)"),
    (
        "parry-hull",
        "Godot, Jolt, Unity, rapier, Avian + hulls",
        "Box, sphere, capsule, cylinder, convex hull (--target parry-hull)",
    ),
    ("usd", "USD physics", "Cube, sphere, capsule, cylinder (--target usd)"),
    ("usd-hull", "USD physics + hulls", "Cube, sphere, capsule, cylinder, convex mesh (--target usd-hull)"),
    ("mujoco", "MuJoCo", "Ellipsoid, box, sphere, capsule, cylinder (--target mujoco)"),
    (
        "mujoco-hull",
        "MuJoCo + hulls",
        "Ellipsoid, box, sphere, capsule, cylinder, hull (--target mujoco-hull)",
    ),
    ("custom", "Custom kinds", "The kinds listed in Kinds (--bv)"),
]

NAMINGS = [
    (
        "UNREAL",
        "Unreal",
        "UBX_ (box), USP_ (sphere), UCP_ (capsule), UCX_ (convex) + the mesh's name + _NN, "
        "as Unreal's FBX importer expects",
    ),
    (
        "GODOT",
        "Godot",
        "The mesh's name + _NN-convcolonly: Godot's importer makes each a static body with its convex shape",
    ),
    ("PLAIN", "Plain", "The mesh's name + _kind_NN"),
]

SPACES = [
    ("LOCAL", "Local", "Fit in the mesh's own coordinates (colliders are exact in its frame)"),
    (
        "WORLD",
        "World",
        "Fit in world space: the primitives stay exact when the object has a non-uniform scale",
    ),
]


def settings_properties():
    """A fresh set of property definitions (each class needs its own)."""
    return {
        "target": EnumProperty(
            name="Target",
            items=TARGETS,
            default="primitives",
            description="The kinds of collider, by engine (bvseg's --target, --bv)",
        ),
        "kinds": StringProperty(
            name="Kinds",
            default="obb,sphere,capsule",
            description="Comma list of ellipsoid, obb, sphere, capsule, cylinder, hull "
            "(used when Target is Custom)",
        ),
        "naming": EnumProperty(
            name="Naming", items=NAMINGS, default="UNREAL", description="How the colliders are named"
        ),
        "tov": FloatProperty(
            name="Outside Volume",
            default=0.3,
            min=1e-4,
            soft_max=2.0,
            step=1,
            precision=3,
            description="Tolerance on the total volume of the colliders outside the mesh, as a "
            "fraction of the mesh's volume (--tov): lower is tighter, with more colliders",
        ),
        "max_protrusion": FloatProperty(
            name="Protrusion",
            default=0.05,
            min=1e-4,
            soft_max=0.5,
            step=0.1,
            precision=3,
            description="Tolerance on how far the colliders reach beyond the surface, "
            "as a fraction of the mesh's bounding-box diagonal (--max-protrusion)",
        ),
        "max_k": IntProperty(
            name="Max Colliders",
            default=96,
            min=1,
            max=4096,
            description="Most colliders per object the tolerances may take (--max-k)",
        ),
        "k": IntProperty(
            name="Exact Count",
            default=0,
            min=0,
            max=4096,
            description="Exactly this many colliders per object, ignoring the tolerances "
            "(--k); 0: as many as the tolerances need",
        ),
        "per_bone": BoolProperty(
            name="Per Bone",
            default=True,
            description="For a mesh deformed by an armature (or a selected armature): bind "
            "each collider to a bone, fitted so that it holds in every pose of the "
            "armature's actions; off: fit the mesh as posed now, parented to the mesh",
        ),
        "space": EnumProperty(
            name="Space", items=SPACES, default="LOCAL", description="Where a static mesh is fitted"
        ),
        "max_hull_vertices": IntProperty(
            name="Hull Vertices",
            default=32,
            min=4,
            max=255,
            description="Most vertices of a convex hull collider (--max-hull-vertices)",
        ),
        "samples": IntProperty(
            name="Samples",
            default=20000,
            min=100,
            max=5000000,
            description="Interior samples of each mesh (--samples): more is finer and slower",
        ),
        "margin": FloatProperty(
            name="Margin",
            default=0.0,
            min=0.0,
            soft_max=1.0,
            precision=4,
            description="Grow every collider outward by this distance (fitting-space units), "
            "beyond the millionth of the largest coordinate always added for Blender's "
            "single precision (--margin)",
        ),
        "rigid_body": BoolProperty(
            name="Rigid Bodies",
            default=True,
            description="Give each collider a passive, animated rigid body with Blender's "
            "collision shape of its kind (box, sphere, capsule, cylinder, convex hull)",
        ),
    }


SETTINGS = tuple(settings_properties())
