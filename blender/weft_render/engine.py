"""weft_render.engine: weft as a Blender render engine (F12, docs/blender.md).

render() exports the scene to a temporary folder (export.py) and renders
that folder with weft.render, so a final render is exactly `weft render` of
the exported scene.json. Progress: Blender's progress bar and the image so
far, about once a second; Esc stops the render and keeps the image so far.
"""

import tempfile
import warnings

import bpy
import numpy as np

from . import export, weft_module


def set_pixels(result, image):
    """weft's (H, W, 3) image, row 0 at the top, into Blender's Combined pass
    (RGBA, row 0 at the bottom)."""
    h, w = image.shape[:2]
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[:, :, :3] = image[::-1]
    result.layers[0].passes["Combined"].rect.foreach_set(rgba.reshape(-1, 4))


class WeftRenderEngine(bpy.types.RenderEngine):
    bl_idname = "WEFT"
    bl_label = "weft"
    bl_use_preview = False
    bl_use_postprocess = True

    def render(self, depsgraph):
        scene = depsgraph.scene
        settings = scene.weft
        try:
            weft = weft_module.get()
        except weft_module.ModuleNotFound as e:
            self.report({"ERROR"}, str(e))
            return
        with tempfile.TemporaryDirectory(prefix="weft-blender-") as folder:
            try:
                exported = export.export_scene(depsgraph, folder)
            except export.ExportError as e:
                self.report({"ERROR"}, str(e))
                return
            for message in exported.warnings:
                self.report({"WARNING"}, message)
            w, h = export.film_size(scene)
            result = self.begin_result(0, 0, w, h)

            def progress(fraction, image):
                self.update_progress(fraction)
                set_pixels(result, image)
                self.update_result(result)
                return not self.test_break()

            try:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always")
                    image, stats = weft.render(str(exported.scene_path), threads=settings.threads,
                                               quiet=True, progress=progress)
            except (ValueError, RuntimeError) as e:
                self.end_result(result, cancel=True)
                self.report({"ERROR"}, "weft: " + exported.explain(e))
                return
            for c in caught:
                self.report({"WARNING"}, exported.explain(c.message))
            set_pixels(result, image)
            self.end_result(result)
            self.update_stats("", f"weft: {stats['spp']} spp in {stats['seconds']:.1f} s" +
                              (" (stopped)" if stats.get("partial") else ""))
