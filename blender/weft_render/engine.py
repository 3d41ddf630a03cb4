"""weft_render.engine: weft as a Blender render engine (F12 and the
viewport's Rendered shading, docs/blender.md).

render() exports the scene to a temporary folder (export.py) and renders
that folder with weft.render, so a final render is exactly `weft render` of
the exported scene.json. Progress: Blender's progress bar and the image so
far, about once a second; Esc stops the render and keeps the image so far.

view_update() and view_draw() are the viewport preview (preview.py): the
scene exported with the viewport's own view, rendered progressively at a
lower resolution on a background thread, and restarted on every change.
"""

import tempfile
import warnings

import bpy
import numpy as np

from . import export, preview, weft_module


def set_pixels(result, image):
    """weft's (H, W, 3) image, row 0 at the top, into Blender's Combined pass
    (RGBA, row 0 at the bottom)."""
    h, w = image.shape[:2]
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[:, :, :3] = image[::-1]
    result.layers[0].passes["Combined"].rect.foreach_set(rgba.reshape(-1, 4))


def _redraw_later(engine, seconds):
    """Asks for a viewport redraw after `seconds` from Blender's main loop
    (tag_redraw is not for other threads); harmless once the engine is gone."""
    def tick():
        try:
            engine.tag_redraw()
        except ReferenceError:
            pass
        return None
    bpy.app.timers.register(tick, first_interval=seconds)


class WeftRenderEngine(bpy.types.RenderEngine):
    bl_idname = "WEFT"
    bl_label = "weft"
    bl_use_preview = False
    bl_use_postprocess = True

    def __init__(self):
        self._preview = None  # PreviewSession of the viewport, made on first use
        self._preview_folder = None
        self._preview_doc = None
        self._preview_status = ""

    def __del__(self):
        try:
            if self._preview is not None:
                self._preview.stop()
            if self._preview_folder is not None:
                self._preview_folder.cleanup()
        except (AttributeError, ReferenceError):
            pass

    # The viewport preview ------------------------------------------------

    def _view(self, context):
        """(camera, film, spp) of the viewport in `context`."""
        settings = context.scene.weft
        camera = preview.viewport_camera(context.region_data.view_matrix,
                                         context.region_data.window_matrix)
        film = preview.preview_film(context.region.width, context.region.height,
                                    settings.preview_scale)
        return camera, film, settings.preview_spp

    def view_update(self, context, depsgraph):
        """The scene changed (or the viewport opened): export it again and restart."""
        try:
            weft = weft_module.get()
        except weft_module.ModuleNotFound as e:
            self._preview_status = str(e)
            return
        if self._preview is None:
            self._preview = preview.PreviewSession(weft, threads=depsgraph.scene.weft.threads)
            self._preview_folder = tempfile.TemporaryDirectory(prefix="weft-preview-")
        try:
            exported = export.export_scene(depsgraph, self._preview_folder.name,
                                           view=self._view(context))
        except export.ExportError as e:
            self._preview.stop()
            self._preview_doc, self._preview_status = None, str(e)
            return
        self._preview_status = "; ".join(exported.warnings)
        self._preview_doc = exported.scene
        self._preview.start(exported.scene, self._preview_folder.name)

    def view_draw(self, context, depsgraph):
        """Draws the preview so far; a moved view or a resized viewport restarts it."""
        if self._preview is None or self._preview_doc is None:
            self.update_stats("", "weft: " + self._preview_status)
            return
        try:
            camera, film, spp = self._view(context)
        except export.ExportError as e:
            self._preview.stop()
            self.update_stats("", "weft: " + str(e))
            return
        doc = self._preview_doc
        if doc["camera"] != camera or doc["film"] != film or doc["render"]["spp"] != spp:
            doc = dict(doc, camera=camera, film=film, render=dict(doc["render"], spp=spp))
            self._preview_doc = doc
            self._preview.start(doc, self._preview_folder.name)
        image, done_spp, done, error = self._preview.snapshot()
        if image is not None:
            self._draw_image(context, depsgraph.scene, image)
        if error:
            self.update_stats("", "weft: " + error)
        else:
            self.update_stats("", f"weft: {done_spp} / {spp} spp" +
                              (f" ({self._preview_status})" if self._preview_status else ""))
        if not done:
            _redraw_later(self, 0.2)

    def _draw_image(self, context, scene, image):
        import gpu
        from gpu_extras.presets import draw_texture_2d
        h, w = image.shape[:2]
        rgba = np.ones((h, w, 4), dtype=np.float32)
        rgba[:, :, :3] = image[::-1]  # a texture's row 0 is the bottom
        pixels = gpu.types.Buffer("FLOAT", w * h * 4, rgba.ravel())
        texture = gpu.types.GPUTexture((w, h), format="RGBA16F", data=pixels)
        gpu.state.blend_set("ALPHA_PREMULT")
        self.bind_display_space_shader(scene)  # the scene's view transform and look
        draw_texture_2d(texture, (0, 0), context.region.width, context.region.height)
        self.unbind_display_space_shader()
        gpu.state.blend_set("NONE")

    # The final render (F12) ----------------------------------------------

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
