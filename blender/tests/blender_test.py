"""The weft add-on inside Blender (docs/blender.md), run by blender/tests/run.py:

    blender -b --factory-startup --python-exit-code 1 --python blender/tests/blender_test.py \
        -- WEFT_BINARY MODULE_DIR WORK_DIR [TEST_NAME ...]

Independent truths: `weft render` of the exported scene (the engine must give
its image), Blender's own evaluation of the curves (the centre and radius of
its bevelled tube), and Cycles (the camera, the environment map's orientation
and the power of point lights with and without a radius and of a sun).
"""

import json
import math
import os
import pathlib
import subprocess
import sys
import unittest

import bpy
import numpy as np
from mathutils import Vector

ROOT = pathlib.Path(__file__).resolve().parents[2]
ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
WEFT_BIN, MODULE_DIR, WORK = ARGS[0], ARGS[1], pathlib.Path(ARGS[2])
ONLY = ARGS[3:]
os.environ["WEFT_PYTHONPATH"] = MODULE_DIR
os.environ.setdefault("WEFT_MODELS_DIR", str(ROOT / "models"))
sys.path.insert(0, str(ROOT / "blender"))
sys.path.insert(0, MODULE_DIR)

import weft  # noqa: E402
import weft_render  # noqa: E402
from weft_render import curves as curve_maths  # noqa: E402
from weft_render import export  # noqa: E402
from weft_render import preview  # noqa: E402

weft_render.register()


def clear():
    for collection in (bpy.data.objects, bpy.data.curves, bpy.data.hair_curves, bpy.data.meshes,
                       bpy.data.lights, bpy.data.cameras, bpy.data.materials, bpy.data.images):
        for block in list(collection):
            if getattr(block, "type", None) != "RENDER_RESULT":
                collection.remove(block)


def new_scene(width=48, height=32, engine="WEFT"):
    clear()
    scene = bpy.context.scene
    scene.render.engine = engine
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.use_compositing = False
    scene.render.use_sequencer = False
    scene.weft.world = "BLENDER"
    scene.weft.spp = 8
    if scene.world is None:
        scene.world = bpy.data.worlds.new("World")
    scene.world.use_nodes = False
    scene.world.color = (0.5, 0.5, 0.5)
    return scene


def link(obj):
    bpy.context.scene.collection.objects.link(obj)
    return obj


def add_camera(eye, target, lens=50.0, name="Camera"):
    cam = link(bpy.data.objects.new(name, bpy.data.cameras.new(name)))
    cam.data.lens = lens
    cam.location = eye
    direction = Vector(target) - Vector(eye)
    cam.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.camera = cam
    return cam


def add_curve(name, splines, bevel=0.05, kind="POLY", resolution=6, interpolation="LINEAR"):
    """splines: [[(x, y, z, radius), ...], ...]"""
    data = bpy.data.curves.new(name, "CURVE")
    data.dimensions = "3D"
    data.bevel_depth = bevel
    data.bevel_resolution = 2
    data.use_fill_caps = False
    for pts in splines:
        sp = data.splines.new(kind)
        sp.resolution_u = resolution
        sp.radius_interpolation = interpolation
        if kind == "BEZIER":
            sp.bezier_points.add(len(pts) - 1)
            for bp, (x, y, z, r) in zip(sp.bezier_points, pts):
                bp.co = (x, y, z)
                bp.handle_left_type = bp.handle_right_type = "AUTO"
                bp.radius = r
        else:
            sp.points.add(len(pts) - 1)
            for p, (x, y, z, r) in zip(sp.points, pts):
                p.co = (x, y, z, 1.0)
                p.radius = r
    return link(bpy.data.objects.new(name, data))


def knit_like(scene):
    """Three wavy yarns, poly and Bezier, 3 plies of fleece."""
    add_camera((0.0, -2.2, 1.2), (0.0, 0.0, 0.0), lens=50)
    for i in range(3):
        pts = [(x, 0.3 * (i - 1), 0.08 * math.sin(2 * math.pi * x + i * math.pi), 1.0)
               for x in np.linspace(-0.9, 0.9, 10)]
        add_curve(f"Yarn.{i}", [pts], bevel=0.09, kind="BEZIER" if i == 1 else "POLY")
    return scene


def render_engine(scene, path):
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return weft.read_image(str(path))


def relative_difference(a, b):
    return float(np.abs(a - b).mean() / max(np.abs(b).mean(), 1e-12))


class EngineMatchesTheCommandLine(unittest.TestCase):
    def test_knit_engine_and_weft_render_of_the_export_agree(self):
        scene = knit_like(new_scene(48, 32))
        work = WORK / "engine"
        engine = render_engine(scene, work / "engine.exr")
        bpy.ops.weft.export_scene(filepath=str(work / "exported" / "scene.json"))
        exported = json.loads((work / "exported" / "scene.json").read_text())
        # Three yarns, and their bevelled tubes (which Blender also lists as
        # meshes) not again as objects.
        self.assertEqual(len(exported["yarns"]), 3)
        self.assertNotIn("objects", exported)
        subprocess.run([WEFT_BIN, "render", str(work / "exported" / "scene.json"), "--out",
                        str(work / "cli.exr"), "--quiet"], check=True)
        cli = weft.read_image(str(work / "cli.exr"))
        self.assertEqual(engine.shape, (32, 48, 3))
        # The same path (exported scene, weft.render): the same image to float rounding.
        np.testing.assert_allclose(engine, cli, rtol=1e-5, atol=1e-6)
        # Not a blank image: the yarns differ from the grey background.
        yarn_pixels = np.abs(engine - 0.5).max(axis=2) > 0.05
        self.assertGreater(yarn_pixels.mean(), 0.1)



def tube_rings(obj, count):
    """Blender's own bevelled tube of a one-spline curve: (centres, radii) of its
    `count` rings of vertices, in weft's world."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    verts = np.array([tuple(obj.matrix_world @ v.co) for v in mesh.vertices])
    evaluated.to_mesh_clear()
    assert len(verts) % count == 0, f"{len(verts)} vertices are not {count} rings"
    rings = verts.reshape(count, len(verts) // count, 3)
    centres = rings.mean(axis=1)
    radii = np.linalg.norm(rings - centres[:, None, :], axis=2).mean(axis=1)
    return np.array([export.to_weft(c) for c in centres]), radii


def read_txt(path):
    curves, current = [], []
    for line in pathlib.Path(path).read_text().splitlines():
        line = line.split("#")[0].strip()
        if not line:
            if current:
                curves.append(np.array(current))
                current = []
            continue
        current.append([float(v) for v in line.split()])
    if current:
        curves.append(np.array(current))
    return curves


class CurvesAreBlendersCurves(unittest.TestCase):
    def check_against_tube(self, obj, work):
        exported = export.export_scene(bpy.context.evaluated_depsgraph_get(), work)
        entry = exported.scene["yarns"][0]
        (points,) = read_txt(work / entry["curves"])
        centres, radii = tube_rings(obj, len(points))
        np.testing.assert_allclose(points[:, :3], centres, atol=2e-5)
        np.testing.assert_allclose(points[:, 3], radii, rtol=2e-3)
        return points

    def test_bezier_radius_taper_in_every_interpolation(self):
        for interpolation in ("LINEAR", "CARDINAL", "BSPLINE", "EASE"):
            with self.subTest(interpolation=interpolation):
                new_scene()
                add_camera((0, -3, 0), (0, 0, 0))
                obj = add_curve("Taper", [[(-1, 0, 0, 1.0), (0, 0.3, 0.2, 0.25), (1, 0, 0.4, 0.6),
                                           (1.5, -0.5, 0.1, 0.9)]],
                                bevel=0.05, kind="BEZIER", resolution=5,
                                interpolation=interpolation)
                obj.location = (0.2, 0.1, -0.3)
                obj.rotation_euler = (0.3, 0.2, 0.5)
                obj.scale = (2.0, 2.0, 2.0)
                bpy.context.view_layer.update()
                points = self.check_against_tube(obj, WORK / "taper" / interpolation)
                self.assertEqual(len(points), 3 * 5 + 1)
                # The ends keep their control radii (bevel 0.05, scale 2), but
                # for B-spline weights, which smooth the first one too.
                first = 0.1 * (5 / 6 + 0.25 / 6) if interpolation == "BSPLINE" else 0.1
                self.assertAlmostEqual(points[0, 3], first, places=6)
                self.assertAlmostEqual(points[-1, 3], 0.09, places=6)

    def test_nurbs_splines_of_each_knot_kind(self):
        for order, endpoint, bezier, weight in ((4, True, False, 1.0), (3, False, False, 1.0),
                                                (4, False, False, 2.5), (3, False, True, 1.0)):
            with self.subTest(order=order, endpoint=endpoint, bezier=bezier, weight=weight):
                new_scene()
                add_camera((0, -3, 0), (0, 0, 0))
                obj = add_curve("Nurbs", [[(-1, 0, 0, 1.0), (-0.4, 0.3, 0.2, 0.4),
                                           (0.2, -0.2, 0.5, 0.8), (0.8, 0.1, 0.1, 1.2),
                                           (1.3, 0.4, -0.2, 0.6)]],
                                bevel=0.03, kind="NURBS", resolution=4)
                spline = obj.data.splines[0]
                spline.order_u = order
                spline.use_endpoint_u = endpoint
                spline.use_bezier_u = bezier
                spline.points[2].co[3] = weight
                obj.rotation_euler = (0.4, 0.0, 0.3)
                bpy.context.view_layer.update()
                folder = f"nurbs-{order}-{int(endpoint)}-{int(bezier)}-{weight}"
                points = self.check_against_tube(obj, WORK / folder)
                self.assertEqual(len(points), 4 * 4)

    def test_poly_spline_keeps_its_points_and_radii(self):
        new_scene()
        add_camera((0, -3, 0), (0, 0, 0))
        obj = add_curve("Poly", [[(-1, 0, 0, 1.0), (0, 0.2, 0.1, 0.5), (1, 0, 0.3, 2.0)]],
                        bevel=0.04)
        points = self.check_against_tube(obj, WORK / "poly")
        np.testing.assert_allclose(points[:, 3], [0.04, 0.02, 0.08], rtol=1e-6)

    def test_catmull_rom_passes_through_its_points(self):
        pts = [(0.0, 0.0, 0.0), (1.0, 0.5, 0.0), (2.0, 0.0, 1.0), (3.0, 1.0, 1.0)]
        positions, radii = curve_maths.catmull_rom_polyline(pts, [1.0, 2.0, 3.0, 4.0], 4, False)
        self.assertEqual(len(positions), 3 * 4 + 1)
        for i, p in enumerate(pts):
            np.testing.assert_allclose(positions[4 * i], p, atol=1e-12)
            self.assertAlmostEqual(radii[4 * i], 1.0 + i)
        # Equally spaced points on a line: a uniform Catmull-Rom spline is that line.
        line, _ = curve_maths.catmull_rom_polyline([(k, 0, 0) for k in range(4)], [1] * 4, 4, False)
        np.testing.assert_allclose([p[0] for p in line[4:9]], [1, 1.25, 1.5, 1.75, 2], atol=1e-12)


class HairCurves(unittest.TestCase):
    def make_hair(self, radii):
        obj = add_curve("Hair", [[(-0.5, 0, 0, radii[0]), (0, 0.1, 0.2, radii[1]),
                                  (0.5, 0, 0, radii[2])]], bevel=0)
        bpy.context.view_layer.update()
        for o in bpy.context.scene.objects:
            o.select_set(o == obj)
        bpy.context.view_layer.objects.active = obj
        bpy.ops.object.convert(target="CURVES")
        hair = bpy.context.view_layer.objects.active
        self.assertEqual(hair.type, "CURVES")
        return hair

    def test_hair_radius_attribute_is_the_yarn_radius(self):
        scene = new_scene(32, 32)
        add_camera((0, -2, 0.3), (0, 0, 0.05))
        hair = self.make_hair([0.02, 0.04, 0.03])
        hair.data.attributes["curve_type"].data[0].value = 1  # poly
        hair.data.update_tag()
        exported = export.export_scene(bpy.context.evaluated_depsgraph_get(), WORK / "hair")
        (points,) = read_txt(WORK / "hair" / exported.scene["yarns"][0]["curves"])
        np.testing.assert_allclose(points[:, 3], [0.02, 0.04, 0.03], rtol=1e-6)
        np.testing.assert_allclose(points[1, :3], export.to_weft((0, 0.1, 0.2)), atol=1e-6)
        image = render_engine(scene, WORK / "hair" / "engine.exr")
        self.assertGreater((np.abs(image - 0.5).max(axis=2) > 0.05).mean(), 0.01)

    def test_catmull_rom_hair_is_resampled(self):
        new_scene()
        add_camera((0, -2, 0.3), (0, 0, 0.05))
        hair = self.make_hair([0.02, 0.02, 0.02])
        hair.data.attributes["curve_type"].data[0].value = 0  # Catmull-Rom, resolution 12
        hair.data.update_tag()
        exported = export.export_scene(bpy.context.evaluated_depsgraph_get(), WORK / "hair-cr")
        (points,) = read_txt(WORK / "hair-cr" / exported.scene["yarns"][0]["curves"])
        self.assertEqual(len(points), 2 * 12 + 1)
        np.testing.assert_allclose(points[12, :3], export.to_weft((0, 0.1, 0.2)), atol=1e-6)


class Errors(unittest.TestCase):
    def test_a_missing_model_names_the_object_and_the_file(self):
        new_scene()
        knit_like(bpy.context.scene)
        yarn = bpy.data.objects["Yarn.2"]
        yarn.weft.model = "FILE"
        yarn.weft.model_file = str(WORK / "no-such-model.json")
        with self.assertRaises(export.ExportError) as caught:
            export.export_scene(bpy.context.evaluated_depsgraph_get(), WORK / "missing")
        self.assertIn("Yarn.2", str(caught.exception))
        self.assertIn("no-such-model.json", str(caught.exception))
        with self.assertRaises(RuntimeError) as op:
            bpy.ops.weft.export_scene(filepath=str(WORK / "missing" / "scene.json"))
        self.assertIn("Yarn.2", str(op.exception))

    def test_a_curve_without_radius_is_refused(self):
        new_scene()
        add_camera((0, -3, 0), (0, 0, 0))
        add_curve("Thin", [[(-1, 0, 0, 1.0), (1, 0, 0, 1.0)]], bevel=0)
        with self.assertRaises(export.ExportError) as caught:
            export.export_scene(bpy.context.evaluated_depsgraph_get(), WORK / "thin")
        self.assertIn("Thin", str(caught.exception))
        self.assertIn("radius", str(caught.exception))

    def test_a_weft_error_names_the_blender_object(self):
        new_scene()
        knit_like(bpy.context.scene)
        bpy.data.objects["Yarn.1"].weft.colour_mode = "FIBER"  # fleece.json takes no colour
        exported = export.export_scene(bpy.context.evaluated_depsgraph_get(), WORK / "colour")
        with self.assertRaises(ValueError) as caught:
            weft.render(str(exported.scene_path), spp=1)
        self.assertIn("(object 'Yarn.1')", exported.explain(caught.exception))


class ViewportPreview(unittest.TestCase):
    """The viewport preview without a screen: its camera from the view and
    projection matrices, and its background renders."""

    def test_viewport_camera_is_the_camera_of_the_same_view(self):
        # Blender's own projection of a camera object (calc_matrix_camera)
        # against export.camera_entry, which reads the lens and the sensor.
        for width, height, fit in ((40, 30, "AUTO"), (24, 36, "VERTICAL"), (36, 24, "HORIZONTAL")):
            with self.subTest(width=width, height=height, fit=fit):
                scene = new_scene(width, height)
                cam = add_camera((0.3, -1.0, 0.4), (2.0, 3.0, 1.5), lens=28)
                cam.data.sensor_fit = fit
                cam.data.sensor_height = 20
                depsgraph = bpy.context.evaluated_depsgraph_get()
                projection = cam.calc_matrix_camera(depsgraph, x=width, y=height)
                ours = preview.viewport_camera(cam.matrix_world.inverted(), projection)
                want = export.camera_entry(scene, cam)
                self.assertAlmostEqual(ours["fov_deg"], want["fov_deg"], places=4)  # float32 matrices
                for key in ("from", "to", "up"):
                    np.testing.assert_allclose(ours[key], want[key], atol=1e-5)
        cam.data.type = "ORTHO"
        ortho = cam.calc_matrix_camera(bpy.context.evaluated_depsgraph_get(), x=40, y=30)
        with self.assertRaisesRegex(export.ExportError, "orthographic"):
            preview.viewport_camera(cam.matrix_world.inverted(), ortho)
        self.assertEqual(preview.preview_film(801, 600, 4), {"width": 200, "height": 150})
        self.assertEqual(preview.preview_film(3, 2, 16), {"width": 1, "height": 1})

    def test_preview_session_renders_restarts_and_reports_errors(self):
        scene = knit_like(new_scene(48, 32))
        scene.weft.spp = 4
        folder = WORK / "preview"
        view = (export.camera_entry(scene, scene.camera), {"width": 24, "height": 16}, 8)
        exported = export.export_scene(bpy.context.evaluated_depsgraph_get(), folder, view=view)
        self.assertEqual(exported.scene["film"], {"width": 24, "height": 16})
        self.assertEqual(exported.scene["render"]["spp"], 8)
        session = preview.PreviewSession(weft, progress_seconds=0.1)
        # A long render first, stopped by the restart: only the second one's image remains.
        long = dict(exported.scene, render=dict(exported.scene["render"], spp=1 << 20))
        session.start(long, folder)
        session.start(exported.scene, folder)
        session.wait(120)
        image, spp, done, error = session.snapshot()
        self.assertTrue(done and error is None and spp == 8)
        # The preview is weft.render of the same scene, to the bit.
        want, _ = weft.render(exported.scene, base_dir=str(folder))
        np.testing.assert_array_equal(image, want)
        self.assertGreater(float(image.mean()), 0.0)
        # A scene weft refuses: the error, not a crash.
        bad = dict(exported.scene, yarns=[dict(exported.scene["yarns"][0], model="missing.json")])
        session.start(bad, folder)
        session.wait(60)
        image, spp, done, error = session.snapshot()
        self.assertTrue(done and image is None and "missing.json" in error)
        session.stop()


def cycles_render(scene, path, samples):
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 1.0
    scene.cycles.max_bounces = 8
    image = render_engine(scene, path)
    scene.render.engine = "WEFT"
    return image


def environment_image(path):
    """A smooth lat-long test map, different in every direction."""
    h, w = 64, 128
    v, u = np.meshgrid((np.arange(h) + 0.5) / h, (np.arange(w) + 0.5) / w, indexing="ij")
    image = np.stack([0.5 + 0.45 * np.cos(2 * np.pi * u), 0.5 + 0.45 * np.sin(2 * np.pi * u),
                      0.1 + 0.8 * v], axis=2)
    weft.save_image(str(path), image)
    return path


def set_environment(scene, path, rotation_z=0.0):
    world = scene.world
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputWorld")
    background = nodes.new("ShaderNodeBackground")
    texture = nodes.new("ShaderNodeTexEnvironment")
    texture.image = bpy.data.images.load(str(path))
    texture.interpolation = "Closest"
    links.new(texture.outputs["Color"], background.inputs["Color"])
    links.new(background.outputs["Background"], out.inputs["Surface"])
    if rotation_z:
        coords = nodes.new("ShaderNodeTexCoord")
        mapping = nodes.new("ShaderNodeMapping")
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, rotation_z)
        links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
        links.new(mapping.outputs["Vector"], texture.inputs["Vector"])


class CyclesAgrees(unittest.TestCase):
    def test_camera_and_environment_map_orientation(self):
        env = environment_image(WORK / "env.exr")
        for width, height, fit, rotation in ((40, 30, "AUTO", 0.0), (24, 36, "VERTICAL", 0.6),
                                             (36, 24, "HORIZONTAL", 0.0)):
            with self.subTest(width=width, height=height, fit=fit, rotation=rotation):
                scene = new_scene(width, height)
                cam = add_camera((0.3, -1.0, 0.4), (2.0, 3.0, 1.5), lens=28)
                cam.data.sensor_fit = fit
                cam.data.sensor_height = 20
                set_environment(scene, env, rotation)
                scene.weft.spp = 16
                folder = WORK / f"env-{width}x{height}"
                cycles = cycles_render(scene, folder / "cycles.exr", 16)
                ours = render_engine(scene, folder / "weft.exr")
                self.assertLess(relative_difference(ours, cycles), 0.03)
                # A map turned a quarter turn the other way is far off: the test can fail.
                exported = export.export_scene(bpy.context.evaluated_depsgraph_get(),
                                               folder / "turned")
                exported.scene["lights"][0]["rotate_deg"] += 90
                turned, _ = weft.render(exported.scene, spp=4, base_dir=str(folder / "turned"))
                self.assertGreater(relative_difference(turned, cycles), 0.1)
        # An image in a colour space weft does not read is refused, not misread.
        scene.world.node_tree.nodes["Environment Texture"].image.colorspace_settings.name = "XYZ"
        with self.assertRaisesRegex(export.ExportError, "env.exr.*colour space XYZ"):
            export.export_scene(bpy.context.evaluated_depsgraph_get(), WORK / "xyz")

    def test_lights_on_a_diffuse_floor(self):
        """A point light with a radius (a weft sphere), one of radius 0 (a weft
        point) and a sun (a weft directional light) against Cycles."""
        for kind, radius in (("POINT", 0.15), ("POINT", 0.0), ("SUN", 0.0)):
            with self.subTest(kind=kind, radius=radius):
                scene = new_scene(32, 32)
                scene.world.color = (0.0, 0.0, 0.0)
                add_camera((0.0, -2.0, 2.0), (0.0, 0.0, 0.0), lens=35)
                bpy.ops.mesh.primitive_plane_add(size=4.0)
                floor = bpy.context.view_layer.objects.active
                material = bpy.data.materials.new("Floor")
                material.use_nodes = True
                nodes = material.node_tree.nodes
                nodes.clear()
                diffuse = nodes.new("ShaderNodeBsdfDiffuse")
                diffuse.inputs["Color"].default_value = (0.6, 0.5, 0.4, 1.0)
                out = nodes.new("ShaderNodeOutputMaterial")
                material.node_tree.links.new(diffuse.outputs["BSDF"], out.inputs["Surface"])
                floor.data.materials.append(material)
                data = bpy.data.lights.new("Lamp", kind)
                light = link(bpy.data.objects.new("Lamp", data))
                data.color = (1.0, 0.9, 0.8)
                if kind == "POINT":
                    data.energy = 200.0
                    data.shadow_soft_size = radius
                    # Out of the picture: Cycles' camera rays miss lamps.
                    light.location = (0.2, -1.2, 2.6)
                else:
                    data.energy = 3.0
                    data.angle = 0.0
                    light.rotation_euler = (0.5, 0.3, 0.2)  # slanted: the cosine matters
                scene.weft.spp = 64
                folder = WORK / f"lamp-{kind.lower()}-{radius}"
                cycles = cycles_render(scene, folder / "cycles.exr", 64)
                ours = render_engine(scene, folder / "weft.exr")
                exported = export.export_scene(bpy.context.evaluated_depsgraph_get(),
                                               folder / "export")
                want = {("POINT", True): "sphere", ("POINT", False): "point",
                        ("SUN", False): "directional"}[(kind, radius > 0)]
                self.assertEqual([l["type"] for l in exported.scene["lights"]], ["constant", want])
                self.assertLess(ours.max(), 50.0)  # the lamp itself is not in the picture
                ratio = ours.reshape(-1, 3).mean(axis=0) / cycles.reshape(-1, 3).mean(axis=0)
                np.testing.assert_allclose(ratio, 1.0, atol=0.03)
                # Where the light falls: 4 x 4 pixel blocks (each weft pixel is
                # noisier than Cycles', which samples a point light's disc and filters).
                def blocks(image):
                    return image.reshape(8, 4, 8, 4, 3).mean(axis=(1, 3))
                self.assertLess(relative_difference(blocks(ours), blocks(cycles)), 0.06)


if __name__ == "__main__":
    loader = unittest.TestLoader()
    suite = unittest.TestSuite()
    for case in list(globals().values()):
        if isinstance(case, type) and issubclass(case, unittest.TestCase):
            for test in loader.loadTestsFromTestCase(case):
                if not ONLY or test._testMethodName in ONLY:
                    suite.addTest(test)
    result = unittest.TextTestRunner(verbosity=2, stream=sys.stdout).run(suite)
    if not result.wasSuccessful():
        raise SystemExit(1)
