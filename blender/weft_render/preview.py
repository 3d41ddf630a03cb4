"""weft_render.preview: the progressive viewport preview (Rendered shading).

The 3D viewport's own view becomes weft's camera (viewport_camera); the
scene is exported as for F12 (export.py) with that camera and a film of the
viewport's size divided by the Preview Scale, and PreviewSession renders it
on a background thread with weft.render, handing each pass's image so far to
the engine's view_draw. Any change to the scene or the view stops the render
in flight and starts again. Blender-free but for the matrices, so the tests
run it headless (blender/tests/blender_test.py).
"""

import math
import threading

from . import export


def viewport_camera(view_matrix, window_matrix):
    """weft's camera entry of a perspective view: the eye and axes from the
    inverse of the view matrix (world to view), the field of view across the
    shorter side from the projection's scale (an OpenGL frustum: [0][0] =
    1 / tan of the half angle across x, [1][1] across y). A view shifted off
    centre (a panned camera view) is drawn centred."""
    p = window_matrix
    if abs(p[3][3]) > 1e-12 or abs(p[3][2]) < 1e-12:
        raise export.ExportError("the viewport is orthographic: weft's camera is a perspective "
                                 "camera (press numpad 5)")
    tan_half = min(1.0 / abs(p[0][0]), 1.0 / abs(p[1][1]))
    return export.camera_from_matrix(view_matrix.inverted(),
                                     2 * math.degrees(math.atan(tan_half)))


def preview_film(region_width, region_height, scale):
    """The preview's film: the viewport's pixels divided by `scale`, at least 1."""
    return {"width": max(1, round(region_width / scale)),
            "height": max(1, round(region_height / scale))}


class PreviewSession:
    """One progressive render at a time on a background thread.

    start(scene, base_dir) stops the render in flight and renders `scene` (a
    weft scene dict) to its render.spp; snapshot() returns what there is so
    far: (image or None, samples per pixel done, done, error message or None).
    """

    def __init__(self, weft, threads=0, progress_seconds=0.2):
        self._weft = weft
        self._threads = threads
        self._progress_seconds = progress_seconds
        self._lock = threading.Lock()
        self._thread = None
        self._stop = threading.Event()
        self._image, self._spp, self._done, self._error = None, 0, False, None
        self.scene = None

    def start(self, scene, base_dir):
        self.stop()
        self.scene = scene
        stop = self._stop = threading.Event()
        with self._lock:
            self._image, self._spp, self._done, self._error = None, 0, False, None
        spp = scene["render"]["spp"]

        def progress(fraction, image):
            with self._lock:
                if not stop.is_set():
                    self._image, self._spp = image, int(round(fraction * spp))
            return not stop.is_set()

        def run():
            try:
                image, stats = self._weft.render(scene, base_dir=str(base_dir),
                                                 threads=self._threads, quiet=True,
                                                 progress=progress,
                                                 progress_seconds=self._progress_seconds)
                with self._lock:
                    if not stop.is_set():
                        self._image, self._spp, self._done = image, stats["spp"], True
            except Exception as e:  # weft's errors reach the viewport's status line
                with self._lock:
                    if not stop.is_set():
                        self._error, self._done = str(e), True

        self._thread = threading.Thread(target=run, name="weft-preview", daemon=True)
        self._thread.start()

    def snapshot(self):
        with self._lock:
            return self._image, self._spp, self._done, self._error

    def wait(self, timeout=None):
        if self._thread is not None:
            self._thread.join(timeout)

    def stop(self):
        """Stops the render in flight (at its next pass) and waits for it."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
