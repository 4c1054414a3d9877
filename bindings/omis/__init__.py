"""omis — optimal multiple importance sampling for baked direct lighting.

The native part (``omis._omis``) is a pybind11 module over the library's C ABI;
this package re-exports it and adds the pure-Python modules (``blender_units``
for Blender/Cycles light conversions, ``demo`` for the built-in scene, ``farm``
for bakes on a Dask cluster, ``job`` for bake jobs and ``python3 -m omis``).
"""
from ._omis import (
    STRATEGIES,
    TECHNIQUES,
    BakeResult,
    Cancelled,
    Scene,
    __version__,
    bake_tile_count,
    bake_vertices,
    combine,
    compose_bake_uv,
    direct_lighting,
    predict_halving,
)
from ._omis import bake_uv as _bake_uv_here


def bake_uv(scene, mesh, width, height, *, client=None, tiles_per_task=None, **options):
    if client is None:
        if tiles_per_task is not None:
            raise ValueError("tiles_per_task: only with client (a distributed bake)")
        return _bake_uv_here(scene, mesh, width, height, **options)
    from .farm import bake_uv_distributed

    return bake_uv_distributed(client, scene, mesh, width, height,
                               tiles_per_task=tiles_per_task, **options)


bake_uv.__doc__ = _bake_uv_here.__doc__.split("\n", 1)[-1] + """
client: a dask.distributed.Client: the lightmap's tiles are baked as Dask tasks
(omis.farm) and the result has the bits of the local bake with the same
settings (a DistributedBakeResult: value, noise, mask, stats, write_exr,
write_png). tiles_per_task: the tasks' size (default: about four tasks per
worker thread). A time_budget is then the whole job's.
"""

__all__ = [
    "__version__", "combine", "STRATEGIES", "TECHNIQUES", "Scene", "direct_lighting", "Cancelled",
    "bake_uv", "bake_vertices", "BakeResult", "predict_halving", "bake_tile_count",
    "compose_bake_uv",
]
