"""omis Bake — direct lighting baked with optimal multiple importance sampling.

Render Properties ▸ Bake (omis), a panel of its own after the render engine's panels
(Cycles' Bake among them), under every engine: the same result as Cycles' Diffuse
bake with only Direct enabled (E_direct/π), with less noise for the time.
Scripts:

    import omis_bake
    stats = omis_bake.bake(bpy.context, samples=256, use_optimal_mis=True)
    bpy.ops.omis.bake(samples=256, target='VERTEX_COLORS')
"""

bl_info = {
    "name": "omis Bake (Optimal MIS)",
    "author": "omis developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties ▸ Render ▸ Bake (omis), after the engine's panels",
    "description": "Bake direct lighting (Cycles' Diffuse ▸ Direct) with optimal multiple "
                   "importance sampling",
    "doc_url": "",
    "category": "Render",
}

if "bpy" in locals():  # F3 ▸ Reload Scripts
    import importlib
    for _module in (errors, native, settings, mesh_cache, export, writeback, job,  # noqa: F821
                    operators, bake_job_files, farm_operators, ui):  # noqa: F821
        importlib.reload(_module)

import bpy  # noqa: E402

from . import (bake_job_files, errors, export, farm_operators, job, mesh_cache,  # noqa: E402,F401
               native, operators, settings, ui, writeback)
from .errors import BakeError, Cancelled  # noqa: E402,F401
from .job import bake  # noqa: E402,F401

__all__ = ["bake", "BakeError", "Cancelled", "register", "unregister"]


def _classes():
    return (settings.OMIS_PG_settings,) + operators.classes + farm_operators.classes + ui.classes


def register():
    native.load()
    for cls in _classes():
        bpy.utils.register_class(cls)
    bpy.types.Scene.omis = bpy.props.PointerProperty(type=settings.OMIS_PG_settings)
    mesh_cache.install()


def unregister():
    running = operators.running
    if running is not None:
        running.cancel()
    mesh_cache.uninstall()
    del bpy.types.Scene.omis
    for cls in reversed(_classes()):
        bpy.utils.unregister_class(cls)
