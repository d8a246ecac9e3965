"""The 3D view sidebar panel, its scene settings, and the add-on's preferences."""

import bpy
from bpy.props import PointerProperty, StringProperty
from bpy.types import AddonPreferences, Panel, PropertyGroup

from . import colliders, props
from .operator import BVSEG_OT_colliders, armature_of


class BvsegSettings(PropertyGroup):
    """The panel's settings, kept with the scene and handed to the operator."""

    __annotations__ = props.settings_properties()


class BvsegPreferences(AddonPreferences):
    bl_idname = __package__

    bvseg_path: StringProperty(
        name="bvseg Executable",
        subtype="FILE_PATH",
        description="The bvseg command-line program (empty: bvseg on PATH)",
    )

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "bvseg_path")
        layout.label(text="Build it with: cargo install --path crates/bvseg-cli (in bvseg's repository)")


class VIEW3D_PT_bvseg(Panel):
    bl_label = "bvseg Colliders"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "bvseg"
    bl_context = "objectmode"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        s = context.scene.bvseg
        col = layout.column()
        col.prop(s, "target")
        if s.target == "custom":
            col.prop(s, "kinds")
        col.prop(s, "naming")
        col = layout.column(heading="Tolerances")
        col.prop(s, "tov")
        col.prop(s, "max_protrusion")
        col = layout.column()
        col.prop(s, "max_k")
        col.prop(s, "k")
        col.prop(s, "per_bone")
        col.prop(s, "space")
        col.prop(s, "rigid_body")
        header, body = layout.panel("bvseg_more", default_closed=True)
        header.label(text="More")
        if body is not None:
            body.prop(s, "max_hull_vertices")
            body.prop(s, "samples")
            body.prop(s, "margin")
        sel = context.selected_objects
        usable = [o for o in sel if o.type in ("MESH", "ARMATURE")]
        row = layout.row()
        row.scale_y = 1.4
        row.enabled = bool(usable)
        op = row.operator(BVSEG_OT_colliders.bl_idname, icon="MESH_ICOSPHERE")
        for name in props.SETTINGS:
            setattr(op, name, getattr(s, name))
        if not usable:
            layout.label(text="Select mesh objects or armatures", icon="INFO")
        else:
            rigged = sum(1 for o in usable if o.type == "ARMATURE" or armature_of(o) is not None)
            n = sum(len(colliders.previous(o)) for o in usable)
            if rigged and s.per_bone:
                layout.label(text="Rigged meshes: colliders on their bones", icon="ARMATURE_DATA")
            if n:
                layout.label(
                    text=f"Replaces {n} collider{'s' if n != 1 else ''} of an earlier run",
                    icon="FILE_REFRESH",
                )


CLASSES = (BvsegSettings, BvsegPreferences, BVSEG_OT_colliders, VIEW3D_PT_bvseg)


def register_settings():
    bpy.types.Scene.bvseg = PointerProperty(type=BvsegSettings)


def unregister_settings():
    del bpy.types.Scene.bvseg
