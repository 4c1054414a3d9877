"""omis — optimal multiple importance sampling for baked direct lighting.

The native part (``omis._omis``) is a pybind11 module over the library's C ABI;
this package re-exports it and adds the pure-Python modules (``blender_units``
for Blender/Cycles light conversions, ``demo`` for the built-in scene).
"""
from ._omis import (
    STRATEGIES,
    TECHNIQUES,
    BakeResult,
    Cancelled,
    Scene,
    __version__,
    bake_uv,
    bake_vertices,
    combine,
    direct_lighting,
    predict_halving,
)

__all__ = [
    "__version__", "combine", "STRATEGIES", "TECHNIQUES", "Scene", "direct_lighting", "Cancelled",
    "bake_uv", "bake_vertices", "BakeResult", "predict_halving",
]
