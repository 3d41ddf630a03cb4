"""weft: a Blender render engine for cloth with the neural yarn model (docs/blender.md)."""

bl_info = {
    "name": "weft",
    "author": "weft",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Render Properties > Render Engine > weft; File > Export > weft scene",
    "description": "Renders curves as yarns with weft's neural appearance model",
    "category": "Render",
}

from . import engine, props, ui  # noqa: E402


def register():
    import bpy
    props.register()
    ui.register()
    bpy.utils.register_class(engine.WeftRenderEngine)


def unregister():
    import bpy
    bpy.utils.unregister_class(engine.WeftRenderEngine)
    ui.unregister()
    props.unregister()
