"""weft_render.weft_module: finds and imports weft's Python module (docs/python.md).

Blender runs its own Python; weft's module (built for /usr/bin/python3, the
same 3.11 as Debian's Blender) is found on sys.path, in $WEFT_PYTHONPATH, in
the add-on's 'Python module folder' preference, in the folder the installer
recorded (paths.json), or in the source tree's build/release/python.
"""

import importlib
import json
import os
import pathlib
import sys

_module = None


class ModuleNotFound(Exception):
    pass


def _candidates():
    import bpy
    here = pathlib.Path(__file__).resolve().parent
    yield os.environ.get("WEFT_PYTHONPATH", "")
    addon = bpy.context.preferences.addons.get(__package__)
    if addon is not None and getattr(addon.preferences, "module_dir", ""):
        yield bpy.path.abspath(addon.preferences.module_dir)
    recorded = here / "paths.json"
    if recorded.exists():
        yield json.loads(recorded.read_text()).get("module_dir", "")
    yield str(here.parent.parent / "build" / "release" / "python")


def get():
    """The weft module; ModuleNotFound with what to do when it is nowhere."""
    global _module
    if _module is not None:
        return _module
    try:
        _module = importlib.import_module("weft")
        return _module
    except ImportError:
        pass
    tried = []
    for folder in _candidates():
        if not folder or not pathlib.Path(folder).is_dir():
            continue
        tried.append(folder)
        sys.path.insert(0, folder)
        try:
            _module = importlib.import_module("weft")
            return _module
        except ImportError:
            sys.path.remove(folder)
    raise ModuleNotFound(
        "weft's Python module is not found (looked in: " + (", ".join(tried) or "nothing") +
        "): build weft (scripts/demo) and install the add-on with scripts/blender-addon, or set "
        "the add-on's 'Python module folder' preference")
