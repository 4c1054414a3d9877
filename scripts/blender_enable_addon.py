"""Enables the omis_bake add-on from the source tree (OMIS_ADDON_DIR) inside Blender.

Run by scripts/blender_run.sh before the user's script; fails the run (exit
code 1) when the add-on cannot be enabled.
"""
import os
import sys

import addon_utils

folder = os.environ.get("OMIS_ADDON_DIR") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "blender_addon")
if folder not in sys.path:
    sys.path.insert(0, folder)

errors = []
module = addon_utils.enable("omis_bake", default_set=True, persistent=True,
                            handle_error=lambda exc: errors.append(exc))
if module is None or errors:
    raise RuntimeError(f"could not enable omis_bake from {folder}: {errors}")
import omis_bake.native  # noqa: E402

if not omis_bake.native.load():
    print(f"omis_bake: warning: {omis_bake.native.error}", file=sys.stderr)
