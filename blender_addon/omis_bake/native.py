"""Finding and loading the compiled `omis` module.

The packaged add-on (scripts/package_addon.sh) bundles the module as the
sub-package ``omis_bake/omis/`` with ``libomis.so.0`` beside the extension; a
development checkout has no such folder and falls back to a plain
``import omis`` from ``sys.path`` (PYTHONPATH=<build>/python, see
scripts/blender_run.sh). Nothing here touches bpy, and a failure is recorded as
one readable sentence for the panel instead of escaping as a traceback.
"""

import ctypes
import glob
import importlib
import os
import sys

# Public state, filled by load().
omis = None          # the omis package, or None
units = None         # omis.blender_units (the one place converting Blender light units)
origin = ""          # "bundled" or "PYTHONPATH", for the panel and the tests
location = ""        # folder the package was loaded from
error = ""           # why loading failed ("" when it worked)

_REQUIRED = ("Scene", "bake_uv", "bake_vertices", "BakeResult", "Cancelled", "__version__")


def _bundled_dir():
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), "omis")


def _load_bundled(folder):
    # The extension finds libomis through its $ORIGIN rpath; loading the
    # library first by absolute path also covers an rpath lost in copying.
    for lib in sorted(glob.glob(os.path.join(folder, "libomis.so*"))):
        ctypes.CDLL(lib, mode=ctypes.RTLD_GLOBAL)
        break
    return importlib.import_module(__package__ + ".omis")


def load():
    """Loads the module once; returns True when it is usable."""
    global omis, units, origin, location, error
    if omis is not None:
        return True
    folder = _bundled_dir()
    try:
        if os.path.isfile(os.path.join(folder, "__init__.py")):
            module, where = _load_bundled(folder), "bundled"
        else:
            module, where = importlib.import_module("omis"), "PYTHONPATH"
        missing = [name for name in _REQUIRED if not hasattr(module, name)]
        if missing:
            raise ImportError(
                f"the omis module at {os.path.dirname(module.__file__)} is too old "
                f"(missing {', '.join(missing)}); rebuild it")
        blender_units = importlib.import_module(module.__name__ + ".blender_units")
    except Exception as exc:  # any failure becomes one sentence for the panel
        error = _explain(exc, folder)
        return False
    omis, units, origin = module, blender_units, where
    location = os.path.dirname(os.path.abspath(module.__file__))
    error = ""
    return True


def _explain(exc, folder):
    text = str(exc).strip() or type(exc).__name__
    if isinstance(exc, ModuleNotFoundError) and getattr(exc, "name", "") == "omis":
        return ("the native module 'omis' is not installed: install the packaged add-on "
                "(build/omis_bake.zip from scripts/package_addon.sh) or start Blender with "
                "PYTHONPATH=<build>/python")
    if "numpy" in text and "version" in text.lower():
        return f"omis was built against another numpy: {text}"
    if sys.version_info[:2] != (3, 11):
        return (f"{text} (this Blender embeds Python {sys.version_info[0]}."
                f"{sys.version_info[1]}; omis is built for Debian's Python 3.11)")
    return f"could not load omis ({type(exc).__name__}): {text}"


def require():
    """The omis package, or a RuntimeError carrying the reason it is unavailable."""
    if not load():
        raise RuntimeError("omis is unavailable: " + error)
    return omis
