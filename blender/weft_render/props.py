"""weft_render.props: weft's settings on scenes and objects (docs/blender.md)."""

import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty,
                       IntProperty, PointerProperty, StringProperty)

from .export import COLOUR_MODELS, PRESET_MODELS

_MODEL_ITEMS = [(m, m, f"the shipped {m} model (models/{m}.json)") for m in PRESET_MODELS] + \
    [(m, m, f"the shipped {m} model: any fiber colour (docs/colour.md)") for m in COLOUR_MODELS] + \
    [("FILE", "File", "a model.json written by weft fit")]
_MODE_ITEMS = [("neural", "Neural", "the fitted neural yarn BSDF on a tube per ply"),
               ("fiber", "Fiber", "explicit fibers: the ground truth, slower"),
               ("dual", "Dual", "the dual-scattering baseline (docs/dual-scattering.md)")]


class WeftSceneSettings(bpy.types.PropertyGroup):
    spp: IntProperty(name="Samples", description="samples per pixel", default=64, min=1,
                     max=1048576)
    seed: IntProperty(name="Seed", description="seed of the random numbers", default=0, min=0)
    max_depth: IntProperty(name="Max Bounces", description="the most scattering events per path",
                           default=1000, min=1, max=10000)
    sampler: EnumProperty(name="Sampler", default="independent",
                          items=[("independent", "Independent", "independent random numbers"),
                                 ("sobol", "Sobol", "Owen-scrambled Sobol' points")])
    mode: EnumProperty(name="Mode", default="PER_OBJECT",
                       items=[("PER_OBJECT", "Per Object", "each yarn's own mode")] + _MODE_ITEMS)
    threads: IntProperty(name="Threads", description="render threads; 0: all cores", default=0,
                         min=0, max=1024)
    world: EnumProperty(name="World", default="BLENDER",
                        items=[("BLENDER", "Blender World",
                                "the world's colour or environment texture"),
                               ("SKY", "weft Sky", "weft's procedural sky (docs/scene-format.md)")])
    sky_scale: FloatProperty(name="Sky Strength", default=1.0, min=0.0)
    preview_spp: IntProperty(name="Viewport Samples",
                             description="samples per pixel of the viewport preview",
                             default=16, min=1, max=4096)
    preview_scale: IntProperty(name="Viewport Pixel Size",
                               description="the viewport preview renders one pixel per this many "
                               "screen pixels", default=4, min=1, max=16)
    light_sampler: EnumProperty(name="Light Sampler", default="uniform",
                                items=[("uniform", "Uniform", "every light alike"),
                                       ("power", "Power", "by each light's power")])


class WeftObjectSettings(bpy.types.PropertyGroup):
    enabled: BoolProperty(name="Render with weft", default=True,
                          description="curves: draw as yarn; meshes: draw as a surface")
    model: EnumProperty(name="Model", items=_MODEL_ITEMS, default="fleece")
    model_file: StringProperty(name="Model File", subtype="FILE_PATH",
                               description="a model.json (weft fit)")
    colour_mode: EnumProperty(
        name="Colour", default="MODEL",
        items=[("MODEL", "Model", "the model's own fiber colour"),
               ("FIBER", "Fiber Colour", "the fiber colour C_TT (a colour model in neural mode)"),
               ("APPEARANCE", "Appearance",
                "the sRGB colour the yarn should look under a white sky (a colour model)")])
    colour: FloatVectorProperty(name="Fiber Colour", subtype="COLOR", size=3, min=0.0, max=1.0,
                                default=(0.8, 0.2, 0.2))
    appearance: FloatVectorProperty(name="Appearance", subtype="COLOR_GAMMA", size=3, min=0.0,
                                    max=1.0, default=(0.7, 0.3, 0.3))
    plies: IntProperty(name="Plies", default=3, min=1, max=16)
    ply_twist: FloatProperty(name="Ply Twist", default=0.3, min=-100.0, max=100.0)
    radius: FloatProperty(name="Radius", default=0.0, min=0.0, unit="LENGTH",
                          description="yarn radius; 0: the curve's bevel depth times its point "
                                      "radii (hair: the radius attribute)")
    mode: EnumProperty(name="Mode", items=_MODE_ITEMS, default="neural")


classes = (WeftSceneSettings, WeftObjectSettings)


def register():
    for c in classes:
        bpy.utils.register_class(c)
    bpy.types.Scene.weft = PointerProperty(type=WeftSceneSettings)
    bpy.types.Object.weft = PointerProperty(type=WeftObjectSettings)


def unregister():
    del bpy.types.Object.weft
    del bpy.types.Scene.weft
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
