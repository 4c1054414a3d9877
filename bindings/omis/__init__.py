"""omis — optimal multiple importance sampling for baked direct lighting.

The native part (``omis._omis``) is a pybind11 module over the library's C ABI;
this package re-exports it and adds the pure-Python helpers.
"""
from ._omis import __version__, combine, STRATEGIES, Scene, direct_lighting, Cancelled

__all__ = ["__version__", "combine", "STRATEGIES", "Scene", "direct_lighting", "Cancelled"]
