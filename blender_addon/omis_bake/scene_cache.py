"""The committed omis scene of the last bake, reused while nothing that reaches omis changed.

Every bake exports the Blender scene again (export.py: cheap, numpy reads), but
committing it (the BVH over every triangle, the emitter shapes, the light
tree) costs as much as a small bake's sampling. An omis scene is a function of
the calls that built it and nothing else, so ``RecordingScene`` forwards every
building call to a new omis.Scene and digests the call with all its arguments
(array bytes, dtype and shape; exact float reprs); ``committed()`` returns the
previous bake's committed scene when the digests match, else commits the new
one and keeps it. The reuse is exact whatever changed in Blender — a light, a
mesh, a modifier, a material, a world: a change either changes a call or never
reaches omis. One scene is kept (the last one baked).
"""

import hashlib
import threading

import numpy as np

# The omis.Scene methods export.py builds a scene with (before commit).
_BUILDERS = frozenset({
    "add_mesh", "set_receiver", "add_point_light", "add_spot_light", "add_sun_light",
    "add_rect_light", "add_ellipse_light", "add_disk_light", "set_light_flags", "set_world",
})

_lock = threading.Lock()
_last = {"digest": None, "scene": None}


def _feed(h, value):
    """Digests a call argument exactly: type, then content."""
    if isinstance(value, np.ndarray):
        a = np.ascontiguousarray(value)
        h.update(f"a{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    elif isinstance(value, (list, tuple)):
        h.update(f"s{len(value)}(".encode())
        for item in value:
            _feed(h, item)
        h.update(b")")
    elif isinstance(value, np.generic):
        _feed(h, value.item())
    elif isinstance(value, (bool, int, float, str)) or value is None:
        h.update(f"{type(value).__name__}:{value!r};".encode())
    else:
        raise TypeError(f"scene_cache: cannot digest a {type(value).__name__} argument")


class RecordingScene:
    """An omis.Scene being built, with the digest of every call that built it."""

    def __init__(self, omis):
        self._scene = omis.Scene()
        self._hash = hashlib.blake2b(digest_size=20)
        self.reused = None   # after committed(): True when the last bake's scene was reused

    def __getattr__(self, name):
        method = getattr(self._scene, name)
        if name not in _BUILDERS:
            return method

        def record(*args, **kwargs):
            _feed(self._hash, name)
            _feed(self._hash, args)
            _feed(self._hash, sorted(kwargs.items()))
            return method(*args, **kwargs)
        return record

    def digest(self):
        return self._hash.hexdigest()

    def committed(self):
        """The committed omis.Scene these calls build: the last bake's when it had the same
        calls, else this one, committed (and kept for the next bake)."""
        digest = self.digest()
        with _lock:
            if _last["digest"] == digest and _last["scene"] is not None:
                self.reused = True
                return _last["scene"]
        self._scene.commit()
        with _lock:
            _last["digest"], _last["scene"] = digest, self._scene
        self.reused = False
        return self._scene


def clear():
    """Forgets the kept scene (frees its memory; the next bake commits anew)."""
    with _lock:
        _last["digest"], _last["scene"] = None, None
