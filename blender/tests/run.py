#!/usr/bin/env python3
"""ctest's blender_addon (docs/blender.md): blender_test.py inside Debian's Blender.

    run.py WEFT_BINARY MODULE_DIR WORK_DIR

Skipped (exit 77, with the reason) when Blender is not installed; scripts/test
installs it (apt-get install blender).
"""

import os
import pathlib
import shutil
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent


def main():
    weft_bin, module_dir, work = sys.argv[1:4]
    blender = shutil.which("blender")
    if blender is None:
        print("blender_addon: skipped: Blender is not installed (apt-get install blender; "
              "scripts/test installs it)")
        return 77
    work = pathlib.Path(work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    env = dict(os.environ)
    # Blender's own settings and caches in the work folder, not the user's.
    env["BLENDER_USER_CONFIG"] = str(work / "config")
    env["BLENDER_USER_SCRIPTS"] = str(work / "scripts")
    cmd = [blender, "-b", "--factory-startup", "--python-exit-code", "1",
           "--python", str(HERE / "blender_test.py"), "--", weft_bin, module_dir, str(work)]
    cmd += sys.argv[4:]
    return subprocess.run(cmd, env=env, timeout=1200).returncode


if __name__ == "__main__":
    sys.exit(main())
