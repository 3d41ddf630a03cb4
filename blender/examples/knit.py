"""A knit built in Blender from curves and rendered with weft (docs/blender.md).

    blender -b --factory-startup --python blender/examples/knit.py -- OUT_DIR [SIZE] [SPP]

weft's knit generator (weft.scene) gives the loops' centre lines; each
course becomes a Blender poly curve with a round bevel (the yarn radius);
alternate courses get the fleece and the polyester colour model with the
colours they should look (Colour: Appearance); a point light with a radius
and weft's sky light them; the weft engine renders it (OUT_DIR/knit.png), then writes the same scene
with File > Export > weft scene (OUT_DIR/exported/scene.json), which
`weft render` draws the same.
"""

import os
import pathlib
import sys
import tempfile

import bpy
from mathutils import Vector

ROOT = pathlib.Path(__file__).resolve().parents[2]
args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
out = pathlib.Path(args[0] if args else "blender-knit").resolve()
size = int(args[1]) if len(args) > 1 else 320
spp = int(args[2]) if len(args) > 2 else 64
os.environ.setdefault("WEFT_MODELS_DIR", str(ROOT / "models"))
sys.path.insert(0, str(ROOT / "blender"))
import weft_render  # noqa: E402
from weft_render import weft_module  # noqa: E402

weft_render.register()
weft = weft_module.get()

# The knit's centre lines from weft's generator, read back as points.
with tempfile.TemporaryDirectory() as tmp:
    info = weft.scene("knit", model=str(ROOT / "models" / "fleece.json"), out=str(pathlib.Path(tmp) / "k"),
                      size=4, radius=0.05)
    points = weft.curves_points(str(pathlib.Path(tmp) / "k" / "yarns.txt"))
radius = info["radius"]

for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
scene = bpy.context.scene
scene.render.engine = "WEFT"
scene.render.resolution_x = scene.render.resolution_y = size
scene.render.resolution_percentage = 100
scene.weft.spp = spp
scene.weft.world = "SKY"
scene.weft.sky_scale = 0.6
scene.render.image_settings.file_format = "PNG"
scene.view_settings.view_transform = "Standard"  # weft's own PNGs: sRGB, no tone curve

rows = sorted(set(int(c) for c in points[:, 0]))
# The colours the courses should look (sRGB, colour by appearance: weft
# finds the fiber colour that gives each, docs/colour.md).
looks = [(0.75, 0.28, 0.26), (0.9, 0.85, 0.74)]
for row in rows:
    data = bpy.data.curves.new(f"Row.{row}", "CURVE")
    data.dimensions = "3D"
    data.bevel_depth = radius
    spline = data.splines.new("POLY")
    row_points = points[points[:, 0] == row][:, 1:]
    spline.points.add(len(row_points) - 1)
    for p, (x, y, z) in zip(spline.points, row_points):
        p.co = (x, -z, y, 1.0)  # weft's +y up is Blender's +z up
    obj = bpy.data.objects.new(f"Row.{row}", data)
    scene.collection.objects.link(obj)
    obj.weft.model = "fleece-colour" if row % 2 == 0 else "polyester-colour"
    obj.weft.colour_mode = "APPEARANCE"
    obj.weft.appearance = looks[row % 2]

lows = points[:, 1:].min(axis=0)
highs = points[:, 1:].max(axis=0)
centre = Vector(((lows[0] + highs[0]) / 2, -(lows[2] + highs[2]) / 2, (lows[1] + highs[1]) / 2))
extent = max(highs - lows)
camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
scene.collection.objects.link(camera)
camera.data.lens = 50
camera.location = centre + Vector((0.35, -1.6, 1.0)) * extent
camera.rotation_euler = (centre - camera.location).to_track_quat("-Z", "Y").to_euler()
scene.camera = camera
lamp = bpy.data.objects.new("Lamp", bpy.data.lights.new("Lamp", "POINT"))
scene.collection.objects.link(lamp)
lamp.data.shadow_soft_size = 0.3 * extent
lamp.data.energy = 40.0 * extent * extent
lamp.location = centre + Vector((-1.0, -1.0, 1.6)) * extent

out.mkdir(parents=True, exist_ok=True)
scene.render.filepath = str(out / "knit.png")
bpy.ops.render.render(write_still=True)
bpy.ops.weft.export_scene(filepath=str(out / "exported" / "scene.json"))
print("weft: wrote", out / "knit.png", "and", out / "exported" / "scene.json")
