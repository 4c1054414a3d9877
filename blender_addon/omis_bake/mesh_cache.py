"""Evaluated meshes read for earlier bakes, kept while Blender reports no change to them.

Reading a mesh's triangles costs far more than anything else in an export:
Blender 3.4 has no raw access to loop triangles, so ``foreach_get`` walks them
one by one (a 16k-triangle emitter: ~10 ms of a 0.05 s bake). The occluders
and emitters of a scene rarely change between bakes, so their reads
(export._LocalMesh: positions, triangles, material indices, in object space)
are kept here and dropped when Blender says they may have changed:

- depsgraph_update_post: an object whose geometry was re-evaluated (an edit,
  a modifier, a driver, anything it depends on) loses its entry; a geometry
  update of anything else that is not a light, image, material, world, scene
  or collection (a mesh, curve, node group, ...) drops every entry;
- frame changes, undo/redo and file loads drop every entry (they re-evaluate
  without reporting updates);
- entries are per view layer, object and object data (name and address).

Only while those handlers are installed (``install``, from the add-on's
register) is anything kept; the baked objects themselves are always read
afresh (their normals and UVs are read with them).
"""

import bpy
from bpy.app.handlers import persistent

_entries = {}           # key -> export._LocalMesh (or None: no faces)
_installed = False
stats = {"hits": 0, "misses": 0}

# Geometry updates of these ID types never change a mesh's read.
_NOT_GEOMETRY = (bpy.types.Light, bpy.types.Image, bpy.types.Material, bpy.types.World,
                 bpy.types.Scene, bpy.types.Collection, bpy.types.ShaderNodeTree)


def key_of(depsgraph, ob_eval):
    original = ob_eval.original
    data = original.data
    return (depsgraph.scene.name_full, depsgraph.view_layer.name,
            original.name_full, original.as_pointer(),
            data.name_full if data is not None else "", data.as_pointer() if data else 0)


def read(depsgraph, ob_eval, reader, used=None):
    """reader(ob_eval), kept for the next bakes while the object is unchanged;
    the key joins `used` (see forget_unused)."""
    if not _installed:
        return reader(ob_eval)
    key = key_of(depsgraph, ob_eval)
    if used is not None:
        used.add(key)
    if key in _entries:
        stats["hits"] += 1
        return _entries[key]
    stats["misses"] += 1
    local = reader(ob_eval)
    _entries[key] = local
    return local


def forget_unused(depsgraph, used):
    """Drops the view layer's entries an export did not read (objects deleted,
    hidden or renamed): what is kept stays what the last bake used."""
    layer = (depsgraph.scene.name_full, depsgraph.view_layer.name)
    for key in [k for k in _entries if k[:2] == layer and k not in used]:
        del _entries[key]


def clear(*_args):
    _entries.clear()


@persistent
def _on_depsgraph_update(_scene, depsgraph):
    if not _entries:
        return
    for update in depsgraph.updates:
        if not update.is_updated_geometry:
            continue
        changed = update.id
        if isinstance(changed, bpy.types.Object):
            name = changed.original.name_full
            for key in [k for k in _entries if k[2] == name]:
                del _entries[key]
        elif not isinstance(changed, _NOT_GEOMETRY):
            _entries.clear()
            return


_CLEARING = ("frame_change_post", "undo_post", "redo_post", "load_pre", "load_post")
_clear_persistent = persistent(clear)


def install():
    global _installed
    handlers = bpy.app.handlers
    if _on_depsgraph_update not in handlers.depsgraph_update_post:
        handlers.depsgraph_update_post.append(_on_depsgraph_update)
    for name in _CLEARING:
        if _clear_persistent not in getattr(handlers, name):
            getattr(handlers, name).append(_clear_persistent)
    _installed = True


def uninstall():
    global _installed
    _installed = False
    handlers = bpy.app.handlers
    if _on_depsgraph_update in handlers.depsgraph_update_post:
        handlers.depsgraph_update_post.remove(_on_depsgraph_update)
    for name in _CLEARING:
        if _clear_persistent in getattr(handlers, name):
            getattr(handlers, name).remove(_clear_persistent)
    clear()
