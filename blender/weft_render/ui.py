"""weft_render.ui: panels, the export operator and the add-on preferences."""

import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ExportHelper

from . import export

ENGINE = "WEFT"


class WeftPanel:
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    COMPAT_ENGINES = {ENGINE}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES


class RENDER_PT_weft(WeftPanel, bpy.types.Panel):
    bl_label = "weft"
    bl_context = "render"

    def draw(self, context):
        s = context.scene.weft
        col = self.layout.column()
        col.use_property_split = True
        for name in ("spp", "seed", "max_depth", "sampler", "mode", "threads", "world"):
            col.prop(s, name)
        if s.world == "SKY":
            col.prop(s, "sky_scale")
        col.prop(s, "light_sampler")
        col.prop(s, "preview_spp")
        col.prop(s, "preview_scale")
        col.operator("weft.export_scene", icon="EXPORT")


class OBJECT_PT_weft(WeftPanel, bpy.types.Panel):
    bl_label = "weft"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and context.object is not None and \
            context.object.type in ("CURVE", "CURVES", "MESH")

    def draw_header(self, context):
        self.layout.prop(context.object.weft, "enabled", text="")

    def draw(self, context):
        ob = context.object
        s = ob.weft
        col = self.layout.column()
        col.use_property_split = True
        col.active = s.enabled
        if ob.type == "MESH":
            col.label(text="A surface: the Principled BSDF's base colour, metallic, roughness")
            return
        col.prop(s, "model")
        if s.model == "FILE":
            col.prop(s, "model_file")
        col.prop(s, "colour_mode")
        if s.colour_mode == "FIBER":
            col.prop(s, "colour")
        elif s.colour_mode == "APPEARANCE":
            col.prop(s, "appearance")
        for name in ("plies", "ply_twist", "radius", "mode"):
            col.prop(s, name)


class WEFT_OT_export_scene(bpy.types.Operator, ExportHelper):
    """Write the scene as a weft scene folder (scene.json and its files) for `weft render`"""
    bl_idname = "weft.export_scene"
    bl_label = "Export to weft"
    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    def invoke(self, context, event):
        self.filepath = "scene.json"
        return super().invoke(context, event)

    def execute(self, context):
        import pathlib
        path = pathlib.Path(self.filepath)
        if path.name != "scene.json":
            self.report({"ERROR"}, "weft writes a folder: choose a file named scene.json")
            return {"CANCELLED"}
        try:
            exported = export.export_scene(context.evaluated_depsgraph_get(), path.parent)
        except export.ExportError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        for message in exported.warnings:
            self.report({"WARNING"}, message)
        self.report({"INFO"}, f"weft scene written: {exported.scene_path}")
        return {"FINISHED"}


def export_menu(self, context):
    self.layout.operator(WEFT_OT_export_scene.bl_idname, text="weft scene (scene.json)")


class WeftPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__
    module_dir: StringProperty(name="Python module folder", subtype="DIR_PATH",
                               description="the folder of weft's Python module "
                                           "(build/release/python)")
    models_dir: StringProperty(name="Models folder", subtype="DIR_PATH",
                               description="weft's models/ folder (the shipped models)")

    def draw(self, context):
        self.layout.prop(self, "module_dir")
        self.layout.prop(self, "models_dir")


# Blender's own panels that apply to weft too: camera lens, light, world
# colour, output and dimensions (the ones Eevee and Workbench share).
_SHARED_PANELS = ("DATA_PT_lens", "DATA_PT_camera", "DATA_PT_camera_dof", "DATA_PT_light",
                  "DATA_PT_EEVEE_light", "EEVEE_WORLD_PT_surface", "WORLD_PT_context_world",
                  "DATA_PT_context_light", "DATA_PT_context_camera", "DATA_PT_curve_texture_space",
                  "DATA_PT_geometry_curve", "DATA_PT_shape_curve", "DATA_PT_active_spline",
                  "MATERIAL_PT_preview", "EEVEE_MATERIAL_PT_context_material",
                  "EEVEE_MATERIAL_PT_surface")

classes = (RENDER_PT_weft, OBJECT_PT_weft, WEFT_OT_export_scene, WeftPreferences)


def register():
    for c in classes:
        bpy.utils.register_class(c)
    bpy.types.TOPBAR_MT_file_export.append(export_menu)
    for name in _SHARED_PANELS:
        panel = getattr(bpy.types, name, None)
        if panel is not None and hasattr(panel, "COMPAT_ENGINES"):
            panel.COMPAT_ENGINES.add(ENGINE)


def unregister():
    for name in _SHARED_PANELS:
        panel = getattr(bpy.types, name, None)
        if panel is not None and hasattr(panel, "COMPAT_ENGINES"):
            panel.COMPAT_ENGINES.discard(ENGINE)
    bpy.types.TOPBAR_MT_file_export.remove(export_menu)
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
