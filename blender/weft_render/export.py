"""weft_render.export: a Blender scene as a weft scene folder (docs/blender.md).

export_scene(depsgraph, folder) writes `scene.json` (docs/scene-format.md)
with the curve files, meshes, models and environment image it names, so that
`weft render folder/scene.json` draws what the render engine draws: the
engine renders exactly this folder.

What maps how:
- Curve objects (poly and Bezier splines) and hair Curves objects (poly and
  Catmull-Rom curves) are yarns: one `.txt` curve file each, in world space,
  with Blender's evaluated points and radii (curves.py).
- Meshes are `objects` of type mesh (an `.obj` file) with a diffuse or
  conductor material read from the Principled BSDF.
- The camera is weft's pinhole camera; point lights with a radius are sphere
  lights of the same power, point lights of radius 0 point lights, suns
  directional lights of their strength; the world is a constant light, an
  envmap, or weft's procedural sky.
Blender is +z up, weft +y up: a Blender point (x, y, z) is weft's (x, z, -y),
a rotation, so nothing is mirrored.
"""

import json
import math
import os
import pathlib
import re
import shutil

import bpy
import mathutils

from . import curves as curve_maths

PRESET_MODELS = ("fleece", "silk", "polyester", "cotton", "gabardine")
COLOUR_MODELS = ("fleece-colour", "polyester-colour", "cotton-colour", "gabardine-colour")
MODES = ("neural", "fiber", "dual")
# Blender's colour spaces whose values are linear Rec.709, as weft reads an envmap.
LINEAR_SPACES = ("Linear", "Non-Color", "Raw")


class ExportError(Exception):
    """A scene weft cannot draw as it is; the message names the object or setting."""


def to_weft(v):
    return [float(v[0]), float(v[2]), -float(v[1])]


def models_dir():
    """Where the shipped models are: $WEFT_MODELS_DIR, the add-on's preference,
    the folder the installer recorded (paths.json), or the source tree's."""
    here = pathlib.Path(__file__).resolve().parent
    candidates = [os.environ.get("WEFT_MODELS_DIR", "")]
    addon = bpy.context.preferences.addons.get(__package__)
    if addon is not None and getattr(addon.preferences, "models_dir", ""):
        candidates.append(bpy.path.abspath(addon.preferences.models_dir))
    recorded = here / "paths.json"
    if recorded.exists():
        candidates.append(json.loads(recorded.read_text()).get("models_dir", ""))
    candidates.append(str(here.parent.parent / "models"))
    for c in candidates:
        if c and (pathlib.Path(c) / "fleece.json").is_file():
            return pathlib.Path(c)
    raise ExportError("weft: the shipped models are not found: set WEFT_MODELS_DIR or the "
                      "add-on's 'Models folder' preference to weft's models/ folder")


def _safe_name(name, used):
    base = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "object"
    candidate, k = base, 1
    while candidate.lower() in used:
        k += 1
        candidate = f"{base}-{k}"
    used.add(candidate.lower())
    return candidate


class _Writer:
    def __init__(self, folder):
        self.folder = pathlib.Path(folder)
        self.used = set()
        self.models = {}  # source path -> relative name in the folder
        self.warnings = []
        self.yarn_objects = []  # yarns[i] is the object of this name

    def model(self, source, owner):
        source = pathlib.Path(source)
        if not source.is_file():
            raise ExportError(f"object '{owner}': weft model file not found: {source}")
        key = str(source.resolve())
        if key not in self.models:
            name = _safe_name(source.stem, self.used) + ".json"
            (self.folder / "models").mkdir(exist_ok=True)
            shutil.copyfile(source, self.folder / "models" / name)
            self.models[key] = "models/" + name
        return self.models[key]


def _yarn_model_path(settings, owner):
    if settings.model == "FILE":
        if not settings.model_file:
            raise ExportError(f"object '{owner}': weft model is 'File' but no model file is set")
        return bpy.path.abspath(settings.model_file)
    return str(models_dir() / f"{settings.model}.json")


def _spline_polylines(obj, matrix, owner):
    """The splines of a curve object as [(positions, radii, closed)] in Blender
    world space; radii before the bevel depth."""
    out = []
    resolution = obj.data.render_resolution_u  # Blender's final renders use it when set
    for index, spline in enumerate(obj.data.splines):
        where = f"object '{owner}', spline {index}"
        if spline.type == "BEZIER":
            pts = [(tuple(p.co), tuple(p.handle_left), tuple(p.handle_right), p.radius)
                   for p in spline.bezier_points]
            if len(pts) < 2:
                raise ExportError(f"{where}: a yarn needs at least 2 points")
            positions, radii = curve_maths.bezier_polyline(
                pts, resolution or spline.resolution_u, spline.use_cyclic_u,
                spline.radius_interpolation)
        elif spline.type == "NURBS":
            pts = [tuple(p.co) + (p.radius,) for p in spline.points]
            if len(pts) < 2:
                raise ExportError(f"{where}: a yarn needs at least 2 points")
            positions, radii = curve_maths.nurbs_polyline(
                pts, spline.order_u, resolution or spline.resolution_u, spline.use_cyclic_u,
                spline.use_endpoint_u, spline.use_bezier_u)
        elif spline.type == "POLY":
            positions = [tuple(p.co)[:3] for p in spline.points]
            radii = [p.radius for p in spline.points]
            if len(positions) < 2:
                raise ExportError(f"{where}: a yarn needs at least 2 points")
        else:
            raise ExportError(f"{where}: {spline.type} splines are not read by weft")
        out.append(([tuple(matrix @ _vec(p)) for p in positions], radii,
                    bool(spline.use_cyclic_u)))
    return out


def _vec(p):
    from mathutils import Vector
    return Vector(p)


_HAIR_TYPES = {0: "CATMULL_ROM", 1: "POLY", 2: "BEZIER", 3: "NURBS"}


def _hair_polylines(obj, matrix, owner):
    data = obj.data
    attrs = data.attributes
    positions = [tuple(p.position) for p in data.points]
    radii = [p.radius for p in data.points] if "radius" in attrs else None

    def per_curve(name, default):
        if name not in attrs:
            return [default] * len(data.curves)
        return [v.value for v in attrs[name].data]

    types = per_curve("curve_type", 0)
    cyclic = per_curve("cyclic", False)
    resolution = per_curve("resolution", 12)
    out = []
    for c in data.curves:
        kind = _HAIR_TYPES.get(types[c.index], str(types[c.index]))
        first, count = c.first_point_index, c.points_length
        pts = positions[first:first + count]
        rad = radii[first:first + count] if radii is not None else [1.0] * count
        if count < 2:
            raise ExportError(f"object '{owner}', curve {c.index}: a yarn needs at least 2 points")
        if kind == "CATMULL_ROM":
            pts, rad = curve_maths.catmull_rom_polyline(pts, rad, max(1, resolution[c.index]),
                                                        bool(cyclic[c.index]))
        elif kind != "POLY":
            raise ExportError(f"object '{owner}', curve {c.index}: {kind} hair curves are not "
                              "read by weft yet; use Catmull-Rom or Poly curves")
        out.append(([tuple(matrix @ _vec(p)) for p in pts], rad, bool(cyclic[c.index])))
    return out, radii is not None


def _has_render_modifiers(obj):
    return any(m.show_render for m in obj.modifiers)


def _edge_polylines(mesh, matrix):
    """The chains of an edge-only mesh (a curve evaluated with its modifiers)."""
    neighbours = {}
    for e in mesh.edges:
        a, b = e.vertices
        neighbours.setdefault(a, []).append(b)
        neighbours.setdefault(b, []).append(a)
    seen, out = set(), []
    starts = [v for v, n in neighbours.items() if len(n) == 1] + list(neighbours)
    for start in starts:
        if start in seen:
            continue
        chain, prev, cur = [start], None, start
        seen.add(start)
        while True:
            nxt = [v for v in neighbours[cur] if v != prev and v not in seen]
            if not nxt:
                break
            prev, cur = cur, nxt[0]
            chain.append(cur)
            seen.add(cur)
        closed = len(chain) > 2 and chain[0] in neighbours[chain[-1]]
        if len(chain) >= 2:
            out.append(([tuple(matrix @ mesh.vertices[v].co) for v in chain], None, closed))
    return out


def _yarn_entry(writer, obj, inst_matrix, settings_owner, scene_settings):
    """One yarn entry for a curve or hair object; writes its curve file."""
    owner = settings_owner.name
    settings = settings_owner.weft
    scale = curve_maths.mean_scale([list(r) for r in inst_matrix.to_3x3()])
    radius_override = settings.radius if settings.radius > 0 else None
    if obj.type == "CURVE":
        if _has_render_modifiers(settings_owner):
            mesh = obj.to_mesh()
            try:
                if len(mesh.polygons) > 0 or radius_override is None:
                    raise ExportError(
                        f"object '{owner}': a curve with modifiers is read from Blender's "
                        "evaluated lines: set its Bevel Depth to 0 and give weft's Radius")
                polylines = _edge_polylines(mesh, inst_matrix)
            finally:
                obj.to_mesh_clear()
            has_radius = False
        else:
            polylines = _spline_polylines(obj, inst_matrix, owner)
            depth = obj.data.bevel_depth
            has_radius = depth > 0 and obj.data.bevel_mode == "ROUND"
            polylines = [(p, [r * depth * scale for r in radii], c) for p, radii, c in polylines]
    else:
        polylines, has_radius = _hair_polylines(obj, inst_matrix, owner)
        polylines = [(p, [r * scale for r in radii], c) for p, radii, c in polylines]
    if not polylines:
        raise ExportError(f"object '{owner}': no curves to draw")
    if radius_override is None and not has_radius:
        raise ExportError(f"object '{owner}': no yarn radius: give the curve a round Bevel Depth "
                          "(hair: a radius attribute) or set weft's Radius")
    if radius_override is not None or not has_radius:
        polylines = [(p, [1.0] * len(p), c) for p, _, c in polylines]
    weft_curves = [([to_weft(p) for p in pos], radii, closed) for pos, radii, closed in polylines]
    for pos, radii, _ in weft_curves:
        if any(not (r > 0 and math.isfinite(r)) for r in radii):
            raise ExportError(f"object '{owner}': a point radius is 0 or negative; "
                              "weft needs every radius > 0")
    (writer.folder / "curves").mkdir(exist_ok=True)
    name = "curves/" + _safe_name(owner, writer.used) + ".txt"
    curve_maths.write_curves_txt(writer.folder / name, weft_curves)

    entry = {"curves": name, "plies": settings.plies, "ply_twist": settings.ply_twist,
             "model": writer.model(_yarn_model_path(settings, owner), owner)}
    if radius_override is not None:
        entry["radius"] = radius_override * scale
    if settings.colour_mode == "FIBER":
        entry["colour"] = [float(c) for c in settings.colour]
    elif settings.colour_mode == "APPEARANCE":
        entry["appearance"] = [float(c) for c in settings.appearance]
    mode = scene_settings.mode if scene_settings.mode != "PER_OBJECT" else settings.mode
    if mode != "neural":
        entry["mode"] = mode
    writer.yarn_objects.append(owner)
    return entry


def _principled(material):
    if material is None:
        return {"type": "diffuse", "reflectance": [0.8, 0.8, 0.8]}
    colour, metallic, roughness = list(material.diffuse_color)[:3], material.metallic, \
        material.roughness
    if material.use_nodes and material.node_tree:
        for node in material.node_tree.nodes:
            if node.type == "BSDF_PRINCIPLED":
                colour = list(node.inputs["Base Color"].default_value)[:3]
                metallic = node.inputs["Metallic"].default_value
                roughness = node.inputs["Roughness"].default_value
                break
            if node.type == "BSDF_DIFFUSE":
                colour, metallic = list(node.inputs["Color"].default_value)[:3], 0.0
                break
    colour = [min(max(float(c), 0.0), 1.0) for c in colour]
    if metallic >= 0.5:
        # Blender's roughness r is GGX alpha r^2 (as in Cycles' Principled BSDF).
        return {"type": "conductor", "colour": colour,
                "roughness": min(max(float(roughness) ** 2, 0.01), 1.0)}
    return {"type": "diffuse", "reflectance": colour}


def _mesh_entry(writer, obj, matrix, owner):
    mesh = obj.to_mesh()
    try:
        mesh.calc_loop_triangles()
        if len(mesh.loop_triangles) == 0:
            return None
        (writer.folder / "meshes").mkdir(exist_ok=True)
        name = "meshes/" + _safe_name(owner, writer.used) + ".obj"
        lines = [f"# {owner}, exported from Blender by weft (weft world: +y up)"]
        for v in mesh.vertices:
            p = to_weft(matrix @ v.co)
            lines.append(f"v {p[0]!r} {p[1]!r} {p[2]!r}")
        for t in mesh.loop_triangles:
            a, b, c = (i + 1 for i in t.vertices)
            lines.append(f"f {a} {b} {c}")
        (writer.folder / name).write_text("\n".join(lines) + "\n")
        material = obj.material_slots[0].material if len(obj.material_slots) else None
        return {"type": "mesh", "file": name, "material": _principled(material)}
    finally:
        obj.to_mesh_clear()


def _light_entry(writer, light, matrix, owner):
    data = light.data
    colour = [float(c) for c in data.color]
    if data.type == "POINT" and data.shadow_soft_size > 0:
        r = data.shadow_soft_size * curve_maths.mean_scale([list(x) for x in matrix.to_3x3()])
        # A point light of power P watts is, in Cycles, a sphere of radiance
        # P / (4 pi^2 r^2) (intensity P / 4 pi over the disc pi r^2 it shows).
        radiance = [c * data.energy / (4 * math.pi ** 2 * r * r) for c in colour]
        return {"type": "sphere", "center": to_weft(matrix.translation), "radius": r,
                "radiance": radiance}
    if data.type == "POINT":
        # Radius 0: a point of intensity P / 4 pi W/sr, the limit of the sphere above.
        return {"type": "point", "position": to_weft(matrix.translation),
                "intensity": [c * data.energy / (4 * math.pi) for c in colour]}
    if data.type == "SUN":
        # Strength is the irradiance (W/m^2) on a surface facing the sun; the
        # light travels along the object's -z axis.
        if data.angle > math.radians(1.0):
            writer.warnings.append(
                f"light '{owner}': a sun of angle {math.degrees(data.angle):.2f} degrees is "
                "drawn as a sun of angle 0 (weft's directional light has no disc)")
        direction = matrix.to_3x3() @ mathutils.Vector((0.0, 0.0, -1.0))
        return {"type": "directional", "direction": to_weft(direction.normalized()),
                "irradiance": [c * data.energy for c in colour]}
    writer.warnings.append(f"light '{owner}' is a {data.type.lower()} light, which weft does "
                           "not have yet: left out (docs/blender.md)")
    return None


def _world_lights(writer, scene):
    settings = scene.weft
    if settings.world == "SKY":
        return [{"type": "sky", "scale": settings.sky_scale}]
    world = scene.world
    if world is None:
        return [{"type": "constant", "radiance": [0.0, 0.0, 0.0]}]
    if not world.use_nodes or world.node_tree is None:
        return [{"type": "constant", "radiance": [float(c) for c in world.color]}]
    output = next((n for n in world.node_tree.nodes
                   if n.type == "OUTPUT_WORLD" and n.is_active_output), None)
    link = output.inputs["Surface"].links[0] if output and output.inputs["Surface"].links else None
    if link is None:
        return [{"type": "constant", "radiance": [0.0, 0.0, 0.0]}]
    background = link.from_node
    if background.type != "BACKGROUND":
        raise ExportError(f"world '{world.name}': weft reads a Background node into the World "
                          f"Output, not {background.bl_idname}; or choose weft's sky "
                          "(Render Properties > weft > World)")
    strength = float(background.inputs["Strength"].default_value)
    colour_input = background.inputs["Color"]
    if not colour_input.links:
        c = colour_input.default_value
        return [{"type": "constant", "radiance": [float(c[i]) * strength for i in range(3)]}]
    texture = colour_input.links[0].from_node
    if texture.type != "TEX_ENVIRONMENT" or texture.image is None or \
            texture.projection != "EQUIRECTANGULAR":
        raise ExportError(f"world '{world.name}': weft reads an Environment Texture "
                          "(equirectangular, with an image) into the Background colour, not "
                          f"'{texture.name}'; or choose weft's sky")
    rotation_z = 0.0
    vector = texture.inputs["Vector"]
    if vector.links:
        mapping = vector.links[0].from_node
        rot = mapping.inputs["Rotation"].default_value if mapping.type == "MAPPING" else None
        if (mapping.type != "MAPPING" or mapping.vector_type != "POINT" or
                abs(rot[0]) > 1e-6 or abs(rot[1]) > 1e-6 or
                any(abs(s - 1) > 1e-6 for s in mapping.inputs["Scale"].default_value) or
                mapping.inputs["Vector"].links and
                mapping.inputs["Vector"].links[0].from_node.type != "TEX_COORD"):
            raise ExportError(f"world '{world.name}': weft reads a Mapping node before the "
                              "Environment Texture only as a rotation about Z")
        rotation_z = rot[2]
    # Cycles looks a direction of azimuth a = atan2(y, x) up at column
    # u = 0.5 - a / 2 pi (direction_to_equirectangular); weft at
    # u = 0.25 - a / 2 pi (a Blender direction in weft's world, docs/scene-format.md),
    # so weft's map turned by 90 degrees about +y is Blender's, less a Mapping
    # node's Z rotation (Cycles looks up the rotated direction).
    rotate_deg = 90.0 - math.degrees(rotation_z)
    image = texture.image
    space = image.colorspace_settings.name
    if space not in LINEAR_SPACES and not (space == "sRGB" and not image.is_float):
        raise ExportError(f"world '{world.name}': image '{image.name}' is in colour space "
                          f"{space}; weft reads linear Rec.709 images ({', '.join(LINEAR_SPACES)}) "
                          "and 8-bit sRGB ones")
    path = bpy.path.abspath(image.filepath, library=image.library)
    if image.packed_file is None and path.lower().endswith((".exr", ".hdr")) and \
            os.path.isfile(path):
        source = path
    else:
        source = str(writer.folder / "world.exr")
        _save_image_linear(image, source)
    name = _safe_name(pathlib.Path(source).stem, writer.used) + pathlib.Path(source).suffix
    if source != str(writer.folder / name):
        shutil.copyfile(source, writer.folder / name)
    return [{"type": "envmap", "file": name, "scale": strength, "rotate_deg": rotate_deg}]


def _save_image_linear(image, path):
    import numpy as np
    from . import weft_module
    w, h = image.size
    pixels = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    rgb = pixels.reshape(h, w, 4)[::-1, :, :3].astype(np.float64)
    if not image.is_float and image.colorspace_settings.name == "sRGB":
        rgb = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    # Otherwise one of LINEAR_SPACES (_world_lights refuses the others).
    weft_module.get().save_image(path, np.ascontiguousarray(rgb))


def camera_entry(scene, camera):
    data = camera.data
    if data.type != "PERSP":
        raise ExportError(f"camera '{camera.name}': weft has a perspective camera only, "
                          f"not {data.type.lower()}")
    if abs(data.shift_x) > 1e-9 or abs(data.shift_y) > 1e-9:
        raise ExportError(f"camera '{camera.name}': weft's camera has no lens shift; set "
                          "Shift X and Y to 0")
    render = scene.render
    if abs(render.pixel_aspect_x - render.pixel_aspect_y) > 1e-9:
        raise ExportError("weft renders square pixels: set the pixel aspect X and Y equal")
    w, h = film_size(scene)
    fit = data.sensor_fit
    if fit == "AUTO":
        sensor, fit = data.sensor_width, ("HORIZONTAL" if w >= h else "VERTICAL")
    elif fit == "HORIZONTAL":
        sensor = data.sensor_width
    else:
        sensor = data.sensor_height
    half = sensor / (2 * data.lens)  # tan of the half angle across the fitted side
    tan_x, tan_y = (half, half * h / w) if fit == "HORIZONTAL" else (half * w / h, half)
    fov = 2 * math.degrees(math.atan(min(tan_x, tan_y)))  # weft: across the shorter side
    return camera_from_matrix(camera.matrix_world.normalized(), fov)


def camera_from_matrix(m, fov_deg):
    """weft's camera entry of a camera-to-world matrix (Blender's cameras look
    down their -z with +y up), fov_deg across the shorter side."""
    eye = m.translation
    forward = m.to_3x3() @ _vec((0.0, 0.0, -1.0))
    up = m.to_3x3() @ _vec((0.0, 1.0, 0.0))
    return {"from": to_weft(eye), "to": to_weft(eye + forward), "up": to_weft(up),
            "fov_deg": fov_deg}


def film_size(scene):
    r = scene.render
    return (max(1, round(r.resolution_x * r.resolution_percentage / 100)),
            max(1, round(r.resolution_y * r.resolution_percentage / 100)))


def dumps(doc):
    """JSON with two-space indents and each list of numbers on one line."""
    text = json.dumps(doc, indent=2)
    return re.sub(r"\[\s+([-+0-9.eE,\s]+?)\s+\]",
                  lambda m: "[" + ", ".join(v.strip() for v in m.group(1).split(",")) + "]",
                  text) + "\n"


class Exported:
    def __init__(self, folder, scene, warnings, yarn_objects):
        self.folder = pathlib.Path(folder)
        self.scene = scene
        self.scene_path = self.folder / "scene.json"
        self.warnings = warnings
        self.yarn_objects = yarn_objects

    def explain(self, message):
        """weft's message with each yarns[i] followed by the Blender object it is."""
        def name(m):
            i = int(m.group(1))
            if i < len(self.yarn_objects):
                return f"{m.group(0)} (object '{self.yarn_objects[i]}')"
            return m.group(0)
        return re.sub(r"yarns\[(\d+)\]", name, str(message))


def export_scene(depsgraph, folder, view=None):
    """Writes the scene folder; returns an Exported. ExportError names what is wrong.
    view: (camera entry, film entry, spp) in place of the scene camera's, its
    resolution and samples (the viewport preview, preview.py)."""
    scene = depsgraph.scene
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    writer = _Writer(folder)
    settings = scene.weft
    if view is not None:
        camera, film, spp = view
    else:
        if scene.camera is None:
            raise ExportError(f"scene '{scene.name}' has no camera")
        w, h = film_size(scene)
        camera = camera_entry(scene, scene.camera.evaluated_get(depsgraph))
        film, spp = {"width": w, "height": h}, settings.spp
    doc = {
        "camera": camera,
        "film": film,
        "render": {"spp": spp, "max_depth": settings.max_depth, "seed": settings.seed,
                   "sampler": settings.sampler},
    }
    lights, yarns, objects = _world_lights(writer, scene), [], []
    for inst in depsgraph.object_instances:
        obj = inst.object
        original = obj.original
        if original.hide_render or (not inst.is_instance and not original.visible_get()
                                    and depsgraph.mode == "VIEWPORT"):
            continue
        owner = inst.parent.original if inst.is_instance and inst.parent else original
        if inst.is_instance and owner == original:
            # An object's own evaluated geometry (a bevelled curve's tube mesh),
            # which Blender lists again as an instance of it: drawn above.
            continue
        matrix = inst.matrix_world.copy()
        if obj.type in ("CURVE", "CURVES"):
            if not original.weft.enabled:
                continue
            yarns.append(_yarn_entry(writer, obj, matrix, original, settings))
        elif obj.type == "MESH":
            if original.weft.enabled:
                entry = _mesh_entry(writer, obj, matrix, original.name)
                if entry:
                    objects.append(entry)
        elif obj.type == "LIGHT":
            entry = _light_entry(writer, obj, matrix, original.name)
            if entry:
                lights.append(entry)
        elif obj.type in ("SURFACE", "FONT", "META", "VOLUME", "POINTCLOUD", "GPENCIL"):
            writer.warnings.append(f"object '{owner.name}' ({obj.type.lower()}) is not drawn "
                                   "by weft: left out")
    doc["lights"] = lights
    if settings.light_sampler != "uniform":
        doc["light_sampler"] = settings.light_sampler
    doc["yarns"] = yarns
    if objects:
        doc["objects"] = objects
    text = dumps(doc)
    tmp = folder / "scene.json.tmp"
    tmp.write_text(text)
    os.replace(tmp, folder / "scene.json")
    return Exported(folder, doc, writer.warnings, writer.yarn_objects)
