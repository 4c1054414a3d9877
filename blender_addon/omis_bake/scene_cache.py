"""The committed omis scene of the last bake, reused while nothing that reaches omis changed.

Every bake exports the Blender scene again (export.py: cheap, numpy reads), but
committing it (the BVH over every triangle, the emitter shapes, the light
tree) costs as much as a small bake's sampling. An omis scene is a function of
the calls that built it and nothing else, so ``RecordingScene`` forwards every
building call to a new omis.Scene and records it with its arguments;
``committed()`` returns the previous bake's committed scene when every call
and argument is the same, bit for bit (arrays: dtype, shape and bytes;
numbers: type and repr), else commits the new one and keeps it. The reuse is
exact whatever changed in Blender — a light, a mesh, a modifier, a material,
a world: a change either changes a call or never reaches omis. One scene is
kept (the last one baked), with its calls (the exported arrays, a fraction of
what the omis scene holds).
"""

import threading

import numpy as np

# The omis.Scene methods export.py builds a scene with (before commit).
_BUILDERS = frozenset({
    "add_mesh", "set_receiver", "add_point_light", "add_spot_light", "add_sun_light",
    "add_rect_light", "add_ellipse_light", "add_disk_light", "set_light_flags", "set_world",
    "set_world_image",
    "set_mesh_lights",
})

_lock = threading.Lock()
_last = {"calls": None, "scene": None}


def _as_bytes(a):
    return np.ascontiguousarray(a).reshape(-1).view(np.uint8)


def same(a, b):
    """True when two call arguments are identical bit for bit (-0.0 is not 0.0)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        if a is b and not a.flags.writeable:  # a kept read-only array (export.mesh_cache)
            return True
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray)
                and a.dtype == b.dtype and a.shape == b.shape
                and np.array_equal(_as_bytes(a), _as_bytes(b)))
    if isinstance(a, dict):  # keyword arguments
        return isinstance(b, dict) and same(sorted(a.items()), sorted(b.items()))
    if isinstance(a, (list, tuple)):
        return (type(a) is type(b) and len(a) == len(b)
                and all(same(x, y) for x, y in zip(a, b)))
    return type(a) is type(b) and repr(a) == repr(b)


class RecordingScene:
    """An omis.Scene being built, with the digest of every call that built it."""

    def __init__(self, omis):
        self._scene = omis.Scene()
        self.calls = []      # (method name, args, kwargs), in order
        self.reused = None   # after committed(): True when the last bake's scene was reused

    def __getattr__(self, name):
        method = getattr(self._scene, name)
        if name not in _BUILDERS:
            return method

        def record(*args, **kwargs):
            self.calls.append((name, args, kwargs))
            return method(*args, **kwargs)
        return record

    def committed(self):
        """The committed omis.Scene these calls build: the last bake's when it had the same
        calls, else this one, committed (and kept for the next bake)."""
        with _lock:
            if _last["scene"] is not None and same(_last["calls"], self.calls):
                self.reused = True
                return _last["scene"]
        self._scene.commit()
        with _lock:
            _last["calls"], _last["scene"] = self.calls, self._scene
        self.reused = False
        return self._scene


def clear():
    """Forgets the kept scene (frees its memory; the next bake commits anew)."""
    with _lock:
        _last["calls"], _last["scene"] = None, None
