"""Blender scene -> omis.Scene: the only code in the add-on that reads Blender data.

Runs on the main thread. Reads the evaluated (viewport) depsgraph — modifiers
applied, instances expanded, world transforms — with numpy ``foreach_get`` and
no Python loop over vertices; lights go through ``omis.blender_units`` (SPEC §4).

Where this differs from Cycles' own bake, and why:
- Cycles bakes a render-mode depsgraph; Python in Blender 3.4 can only evaluate
  the viewport one. Objects hidden in the viewport but enabled for rendering,
  and modifiers whose viewport settings differ from their render settings, are
  reported as warnings rather than silently baked differently.
- The baked surface's closure follows its material (``material_receiver``):
  Principled BSDF → the Principled diffuse at its Roughness, Diffuse BSDF →
  Oren–Nayar, evaluated as Cycles' Diffuse bake does; other surfaces are baked
  as Lambert with a warning.
- The material's *active* Image Texture node is read from ``nodes.active``
  (Cycles' "active texture" flag has no Python accessor); a tree whose active
  node is not an image node but holds exactly one Image Texture node uses that.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from . import mesh_cache
from .errors import BakeError
from .scene_cache import RecordingScene

# Object types Cycles turns into triangles (occluders / emitters).
_GEOMETRY_TYPES = {'MESH', 'CURVE', 'SURFACE', 'FONT', 'META'}
# Byte images: colour spaces written without a transform, and sRGB.
_RAW_SPACES = {'Non-Color', 'Raw', 'Linear', 'Linear ACES', 'Linear ACEScg', 'XYZ'}
_SRGB_SPACES = {'sRGB'}


@dataclass
class Part:
    """One omis mesh that is baked: the triangles of one object sharing one target."""
    object_name: str
    mesh_id: int
    triangles: int
    tri_loops: np.ndarray = None   # (T, 3) loop indices of the evaluated mesh (color attributes)
    uv_area: float = 0.0           # its triangles' area in UV space (the image is 1)


@dataclass
class ImageTarget:
    image: object                  # bpy.types.Image (original datablock)
    name: str
    width: int
    height: int
    encoding: str                  # 'float', 'srgb' or 'raw' (byte without transform)
    clear_alpha: float             # Cycles clears RGBA images to alpha 0, RGB ones to 1
    parts: list = field(default_factory=list)


@dataclass
class AttributeTarget:
    object_name: str
    mesh: object                   # bpy.types.Mesh (original datablock)
    attribute_name: str
    domain: str                    # 'POINT' or 'CORNER'
    n_loops: int
    n_verts: int
    loop_vertex: np.ndarray        # (L,) vertex of each loop
    parts: list = field(default_factory=list)


@dataclass
class Export:
    scene: object                  # scene_cache.RecordingScene (an omis.Scene being built)
    images: list                   # ImageTarget
    attributes: list               # AttributeTarget
    warnings: list
    counts: dict                   # what went into the scene (for stats and tests)
    lights: list                   # one dict per light added (kind and the values passed)
    has_light: bool                # any light, emitter or world at all


@dataclass
class _LocalMesh:
    """An evaluated mesh in object space, ready to be transformed per instance.
    Only baked objects carry their loops, shading normals and UVs: omis shades
    nothing else, and every other mesh (occluders, emitters) is positions and
    triangles to it."""
    co: np.ndarray                 # (V, 3) float64
    tri_vert: np.ndarray           # (T, 3) int32
    material_index: np.ndarray     # (T,) int32
    tri_loop: np.ndarray = None    # (T, 3) int32, bake objects only
    loop_normal: np.ndarray = None # (L, 3) float64, bake objects only
    flat: np.ndarray = None        # (T,) bool: the triangle's polygon is flat-shaded
    uv: np.ndarray = None          # (L, 2) float32, active UV map, bake objects only
    loop_vertex: np.ndarray = None # (L,) int32, bake objects only
    n_loops: int = 0
    placed: tuple = None           # (matrix bytes, positions) of a kept read's last placement


def _read_mesh(me, baked):
    me.calc_loop_triangles()
    nv, nt = len(me.vertices), len(me.loop_triangles)
    co = np.empty(nv * 3, np.float32)
    me.vertices.foreach_get("co", co)
    tri_vert = np.empty(nt * 3, np.int32)
    me.loop_triangles.foreach_get("vertices", tri_vert)
    mat = np.empty(nt, np.int32)
    me.loop_triangles.foreach_get("material_index", mat)
    local = _LocalMesh(co.reshape(-1, 3).astype(np.float64), tri_vert.reshape(-1, 3), mat)
    if not baked:
        # Split normals are the costly part of a read (a 16k-triangle emitter:
        # about half its export); only shading needs them.
        return local
    me.calc_normals_split()
    nl = len(me.loops)
    tri_loop = np.empty(nt * 3, np.int32)
    me.loop_triangles.foreach_get("loops", tri_loop)
    ln = np.empty(nl * 3, np.float32)
    me.loops.foreach_get("normal", ln)
    smooth = np.empty(len(me.polygons), bool)
    me.polygons.foreach_get("use_smooth", smooth)
    # With Auto Smooth (split or custom normals) Cycles shades every face with
    # the loop normals; otherwise flat faces use each triangle's own normal.
    smooth |= bool(getattr(me, "use_auto_smooth", False))
    tri_poly = np.empty(nt, np.int32)
    me.loop_triangles.foreach_get("polygon_index", tri_poly)
    local.tri_loop = tri_loop.reshape(-1, 3)
    local.loop_normal = ln.reshape(-1, 3).astype(np.float64)
    local.flat = ~smooth[tri_poly]
    local.n_loops = nl
    layer = me.uv_layers.active
    if layer is not None:
        uv = np.empty(nl * 2, np.float32)
        layer.data.foreach_get("uv", uv)
        local.uv = uv.reshape(-1, 2)
    lv = np.empty(nl, np.int32)
    me.loops.foreach_get("vertex_index", lv)
    local.loop_vertex = lv
    return local


def _world_positions(local, matrix):
    """local.co placed by matrix, float32; a kept read keeps its last placement
    (read-only), so an unchanged object costs no transform and its array
    compares by identity in scene_cache."""
    key = matrix.tobytes()
    kept = local.placed
    if kept is not None and kept[0] == key:
        return kept[1]
    positions = (local.co @ matrix[:3, :3].T + matrix[:3, 3]).astype(np.float32)
    if not local.co.flags.writeable:  # a read mesh_cache keeps
        positions.flags.writeable = False
        local.placed = (key, positions)
    return positions


def _read_shared_mesh(ob_eval):
    """An occluder's or emitter's read, read-only: mesh_cache keeps it for later bakes."""
    local = _to_local_mesh(ob_eval, baked=False)
    if local is not None:
        for array in (local.co, local.tri_vert, local.material_index):
            array.flags.writeable = False
    return local


def _to_local_mesh(ob_eval, baked):
    """The evaluated geometry of an object, or None if it has none."""
    try:
        me = ob_eval.to_mesh()
    except RuntimeError:
        return None
    if me is None:
        return None
    try:
        if len(me.polygons) == 0:
            return None
        return _read_mesh(me, baked)
    finally:
        ob_eval.to_mesh_clear()


# ---------------------------------------------------------------------------
# Materials: emission and the active image


def _socket_value(socket):
    v = socket.default_value
    try:
        return tuple(float(x) for x in v)
    except TypeError:
        return float(v)


def _linked_from(socket):
    for link in socket.links:
        if not link.is_muted and link.is_valid:
            return link.from_node, link.from_socket
    return None, None


def _shader_emission(node, problems, name, depth=0):
    """RGB emitted radiance of a shader node tree below `node`, or None."""
    if node is None or depth > 64 or node.mute:
        return None
    kind = node.type
    if kind == 'REROUTE':
        return _shader_emission(_linked_from(node.inputs[0])[0], problems, name, depth + 1)
    if kind in ('EMISSION', 'BSDF_PRINCIPLED'):
        color_in = node.inputs['Color' if kind == 'EMISSION' else 'Emission']
        strength_in = node.inputs['Strength' if kind == 'EMISSION' else 'Emission Strength']
        if color_in.is_linked or strength_in.is_linked:
            which = color_in.name if color_in.is_linked else strength_in.name
            problems.append(f'material "{name}": textured emission is not supported '
                            f'({node.name} ▸ {which} is linked); treated as not emitting')
            return None
        color = _socket_value(color_in)[:3]
        strength = _socket_value(strength_in)
        if strength <= 0 or max(color) <= 0:
            return None
        return color, strength
    if kind == 'ADD_SHADER':
        parts = [_shader_emission(_linked_from(s)[0], problems, name, depth + 1)
                 for s in node.inputs[:2]]
        return _sum_emission(parts, [1.0, 1.0])
    if kind == 'MIX_SHADER':
        fac_in = node.inputs[0]
        parts = [_shader_emission(_linked_from(s)[0], problems, name, depth + 1)
                 for s in node.inputs[1:3]]
        if all(p is None for p in parts):
            return None
        if fac_in.is_linked:
            problems.append(f'material "{name}": emission behind a Mix Shader with a linked '
                            f'factor ({node.name}) is not supported; treated as not emitting')
            return None
        f = min(max(_socket_value(fac_in), 0.0), 1.0)
        return _sum_emission(parts, [1.0 - f, f])
    if kind == 'GROUP' and node.node_tree is not None:
        inner = any(n.type == 'EMISSION' or (n.type == 'BSDF_PRINCIPLED'
                                             and (n.inputs['Emission'].is_linked
                                                  or max(_socket_value(n.inputs['Emission'])[:3]) > 0))
                    for n in node.node_tree.nodes)
        if inner:
            problems.append(f'material "{name}": emission inside node group "{node.name}" is '
                            f'not supported; treated as not emitting')
    return None


def _sum_emission(parts, weights):
    total, any_part = [0.0, 0.0, 0.0], False
    for part, w in zip(parts, weights):
        if part is None or w == 0:
            continue
        color, strength = part
        any_part = True
        for k in range(3):
            total[k] += w * strength * color[k]
    if not any_part or max(total) <= 0:
        return None
    return tuple(total), 1.0


def _active_output(tree, kinds):
    best = None
    for node in tree.nodes:
        if node.bl_idname in kinds and getattr(node, "target", 'ALL') in ('ALL', 'CYCLES'):
            if node.is_active_output:
                return node
            best = best or node
    return best


def material_emission(material, units, problems):
    """Constant emitted radiance (RGB) of a material, or None (SPEC §4 mesh emission)."""
    if material is None or not material.use_nodes or material.node_tree is None:
        return None
    out = _active_output(material.node_tree, {'ShaderNodeOutputMaterial'})
    if out is None:
        return None
    found = _shader_emission(_linked_from(out.inputs['Surface'])[0], problems, material.name)
    if found is None:
        return None
    color, strength = found
    radiance = units.mesh_emission(strength, color)
    return radiance if max(radiance) > 0 else None


def material_transparency(material, problems):
    """Transparency omis does not model (SPEC §4: Cycles lets shadow rays through
    transparent surfaces): says so in `problems`."""
    if material is None or not material.use_nodes or material.node_tree is None:
        return
    for node in material.node_tree.nodes:
        if node.mute:
            continue
        alpha = node.inputs.get("Alpha") if node.type == 'BSDF_PRINCIPLED' else None
        if node.type == 'BSDF_TRANSPARENT' or (alpha is not None and (
                alpha.is_linked or _socket_value(alpha) < 1.0)):
            problems.append(f'material "{material.name}": its transparency ({node.name}) is '
                            f'ignored: omis treats its surfaces as opaque to shadows')
            return


def _follow_reroutes(node):
    while node is not None and node.type == 'REROUTE':
        node, _ = _linked_from(node.inputs[0])
    return node


def _unlinked_value(node, name, material, problems):
    socket = node.inputs[name]
    if socket.is_linked:
        problems.append(f'material "{material.name}": {node.name} ▸ {name} is linked; omis '
                        f'uses its unlinked value {_socket_value(socket):.3g}')
    return _socket_value(socket)


def _ignored_shading(node, out, material, problems):
    """Inputs that bend Cycles' shading normal (SPEC §4 receiver normal), which omis
    does not model: it shades with the mesh's own normals."""
    normal = node.inputs.get("Normal")
    if normal is not None and _linked_from(normal)[0] is not None:
        problems.append(f'material "{material.name}": {node.name} ▸ Normal is linked (a '
                        f'normal map or bump), which omis ignores: it shades with the mesh\'s '
                        f'normals')
    displacement = out.inputs.get("Displacement")
    if displacement is not None and _linked_from(displacement)[0] is not None:
        problems.append(f'material "{material.name}": its displacement (Material Output ▸ '
                        f'Displacement) is ignored by omis')


def material_receiver(material, problems):
    """(model, roughness) of the diffuse closure Cycles' Diffuse bake evaluates on
    this material (omis Scene.set_receiver), or None for Lambert.

    Principled BSDF → its diffuse ("principled", Roughness); Diffuse BSDF →
    Oren–Nayar at its Roughness (Lambert at 0). No material or no nodes is
    Cycles' default diffuse (Lambert). Anything else is baked as Lambert with a
    warning in `problems`."""
    if material is None or not material.use_nodes or material.node_tree is None:
        return None
    out = _active_output(material.node_tree, {'ShaderNodeOutputMaterial'})
    node = _follow_reroutes(_linked_from(out.inputs['Surface'])[0]) if out else None
    if node is None or node.mute:
        problems.append(f'material "{material.name}" has no surface shader; omis bakes it as '
                        f'Lambert (Cycles\' Diffuse bake gives 0 there)')
        return None
    _ignored_shading(node, out, material, problems)
    if node.type == 'BSDF_DIFFUSE':
        roughness = _unlinked_value(node, "Roughness", material, problems)
        return ("oren-nayar", max(0.0, roughness)) if roughness > 0 else None
    if node.type == 'BSDF_PRINCIPLED':
        roughness = _unlinked_value(node, "Roughness", material, problems)
        for name in ("Subsurface", "Sheen"):
            if node.inputs[name].is_linked or _socket_value(node.inputs[name]) > 0:
                problems.append(f'material "{material.name}": {name} is not modelled by omis '
                                f'(only the Principled diffuse is)')
        for name in ("Metallic", "Transmission"):
            if node.inputs[name].is_linked:
                problems.append(f'material "{material.name}": {name} is linked (textured); omis '
                                f'bakes the Principled diffuse everywhere (Cycles\' Diffuse bake '
                                f'gives 0 where it reaches 1)')
        metallic = _socket_value(node.inputs["Metallic"])
        transmission = _socket_value(node.inputs["Transmission"])
        if not node.inputs["Metallic"].is_linked and not node.inputs["Transmission"].is_linked \
                and (metallic >= 1.0 or transmission >= 1.0):
            problems.append(f'material "{material.name}" has no diffuse part (Metallic or '
                            f'Transmission 1): Cycles\' Diffuse bake gives 0, omis bakes its '
                            f'Principled diffuse')
        return ("principled", max(0.0, roughness))
    problems.append(f'material "{material.name}": its surface ({node.name}) is neither a '
                    f'Principled nor a Diffuse BSDF; omis bakes it as Lambert')
    return None


def _nodes_feeding(node, seen=None):
    """Names of the nodes whose outputs reach `node` through unmuted links (node groups'
    insides are not entered: a group node stands for them)."""
    seen = set() if seen is None else seen
    for socket in node.inputs:
        for link in socket.links:
            if link.is_muted or not link.is_valid or link.from_node.name in seen:
                continue
            seen.add(link.from_node.name)
            _nodes_feeding(link.from_node, seen)
    return seen


def bake_image_node(material, notes=None):
    """(node, problem): the Image Texture node a material bakes into, as Cycles picks it
    as far as Python can tell. Cycles bakes into the last Image Texture node made active
    (a flag Python cannot read); Python sees the active node only. So: the active node
    if it is an Image Texture; else the only Image Texture node; else the only one that
    feeds nothing of the material's output (the others are its textures: a normal map,
    a colour), saying so in `notes`; else a problem saying how to choose."""
    nodes = material.node_tree.nodes
    if nodes.active is not None and nodes.active.type == 'TEX_IMAGE':
        return nodes.active, None
    images = [n for n in nodes if n.type == 'TEX_IMAGE']
    if len(images) == 1:
        return images[0], None
    if not images:
        return None, f'material "{material.name}" has no Image Texture node'
    out = _active_output(material.node_tree, {'ShaderNodeOutputMaterial'})
    used = _nodes_feeding(out) if out is not None else set()
    unused = [n for n in images if n.name not in used]
    if len(unused) == 1:
        if notes is not None:
            notes.append(f'material "{material.name}": no Image Texture node is active; baked '
                         f'into "{unused[0].name}", the one not linked to the shader (click '
                         f'another to bake into it)')
        return unused[0], None
    among = unused if unused else images
    names = ", ".join(f'"{n.name}"' for n in among[:4]) + (" …" if len(among) > 4 else "")
    return None, (f'material "{material.name}" has {len(among)} Image Texture nodes that could '
                  f'be the bake target ({names}): in the Shader Editor click the one to bake '
                  f'into (it becomes the active node), or unlink the others from the shader')


def active_image(material, notes=None):
    """(image, problem): the image of the Image Texture node the material bakes into
    (bake_image_node; how it was chosen, when not by the artist, in `notes`)."""
    if material is None:
        return None, "no material"
    if not material.use_nodes or material.node_tree is None:
        return None, f'material "{material.name}" does not use nodes'
    node, problem = bake_image_node(material, notes)
    if node is None:
        return None, problem
    if node.image is None:
        return None, (f'the Image Texture node "{node.name}" of material "{material.name}" has '
                      f'no image: choose or create one there')
    return node.image.original, None


def _image_target(image, object_name):
    if image.source == 'TILED':
        # Blender 3.4's Python reads and writes only an image's first tile.
        raise BakeError(f'image "{image.name}" (object "{object_name}") is a UDIM tiled '
                        f'image, which omis cannot write: bake into a single (non-tiled) image '
                        f'with the UVs in the 0–1 square — for several tiles, one material and '
                        f'image per tile — or use Cycles\' Bake')
    width, height = int(image.size[0]), int(image.size[1])
    if width <= 0 or height <= 0:
        raise BakeError(f'image "{image.name}" (object "{object_name}") has no pixels: '
                        f'generate it or reload its file')
    if image.is_float:
        encoding = 'float'
    else:
        space = image.colorspace_settings.name
        if space in _SRGB_SPACES:
            encoding = 'srgb'
        elif space in _RAW_SPACES:
            encoding = 'raw'
        else:
            raise BakeError(f'image "{image.name}": 8-bit images in colour space "{space}" are '
                            f'not supported; use a float image or sRGB / Non-Color')
    clear_alpha = 0.0 if image.depth in (32, 64, 128) else 1.0
    return ImageTarget(image, image.name, width, height, encoding, clear_alpha)


def _angle_upto_pi(angle):
    # Blender stores π as the float32 3.1415927 > math.pi, which omis.blender_units
    # refuses as a spread / spot size; the intended value is π.
    return min(float(angle), math.pi)


# ---------------------------------------------------------------------------
# Visibility


def _render_visible_names(view_layer):
    """Names of the objects in collections enabled for rendering in this view layer."""
    names = set()

    def walk(lc, visible):
        visible = visible and not lc.exclude and not lc.collection.hide_render
        if visible:
            names.update(o.name_full for o in lc.collection.objects)
        for child in lc.children:
            walk(child, visible)

    walk(view_layer.layer_collection, True)
    return names


def _modifier_differences(ob):
    notes = []
    for md in getattr(ob, "modifiers", ()):
        if md.show_viewport != md.show_render:
            notes.append(f'{md.name} is {"on" if md.show_viewport else "off"} in the viewport '
                         f'but {"on" if md.show_render else "off"} for rendering')
        elif md.show_viewport and md.type in ('SUBSURF', 'MULTIRES'):
            if md.levels != md.render_levels:
                notes.append(f'{md.name} has {md.levels} viewport levels but '
                             f'{md.render_levels} render levels')
    return notes


# ---------------------------------------------------------------------------
# The exporter


def _uv_area(corner_uvs):
    """Total area of triangles given by their corners' UVs (3T, 2)."""
    uv = np.asarray(corner_uvs, np.float64).reshape(-1, 3, 2)
    e1, e2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    return float(0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum())


def _corner_normals(positions, tris, loop_normals, flat):
    """Per-corner shading normals (3T, 3) float32. Cycles shades a flat-shaded
    polygon with each triangle's own geometric normal (its Ng), not the
    polygon's normal that Blender's loop normals carry: on a non-planar quad
    (Suzanne has many) the two differ by tens of degrees."""
    out = np.array(loop_normals, np.float64).reshape(-1, 3, 3)
    if flat is not None and flat.any():
        p = positions[tris[flat]].astype(np.float64)
        ng = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        length = np.linalg.norm(ng, axis=1, keepdims=True)
        ok = length[:, 0] > 0
        ng[ok] /= length[ok]
        tri_normals = out[flat]
        tri_normals[ok] = ng[ok][:, None, :]
        out[flat] = tri_normals
    return np.ascontiguousarray(out.reshape(-1, 3), dtype=np.float32)


class _Exporter:
    def __init__(self, context, omis, units, bake_objects, target):
        self.context = context
        self.omis = omis
        self.units = units
        self.target = target
        # Records its calls so that an unchanged scene is committed once (scene_cache.py).
        self.scene = RecordingScene(omis)
        self.warnings = []
        self.lights = []
        self.counts = {"instances": 0, "meshes": 0, "triangles": 0, "vertices": 0,
                       "emissive_meshes": 0, "lights": {}, "world": False,
                       "receivers": {}}
        self.bake_objects = bake_objects
        self.bake_names = {ob.name_full for ob in bake_objects}
        self.images = {}          # image name_full -> ImageTarget
        self._emission_cache = {}
        self._receiver_cache = {}
        self._mesh_cache = {}      # this export's reads of shared meshes (instances)
        self.depsgraph = None
        self._shared_used = set()  # mesh_cache keys this export read
        self._bake_local = {}     # object name -> _LocalMesh
        self._bake_slot_images = {}  # object name -> [ImageTarget or None] per slot
        self._attr_target = {}    # object name -> AttributeTarget

    def warn(self, text):
        if text not in self.warnings:
            self.warnings.append(text)

    # -- validation of the objects to bake (before anything is exported) --

    def check_bake_objects(self, depsgraph, visible_names):
        if not self.bake_objects:
            raise BakeError("nothing selected: select the mesh objects to bake")
        for ob in self.bake_objects:
            if ob.type != 'MESH':
                raise BakeError(f'"{ob.name}" is not a mesh ({ob.type.lower()}): select only '
                                f'mesh objects to bake')
        for ob in self.bake_objects:
            if ob.hide_render or ob.name_full not in visible_names:
                raise BakeError(f'"{ob.name}" is not enabled for rendering')
            ob_eval = ob.evaluated_get(depsgraph)
            local = _to_local_mesh(ob_eval, baked=True)
            if local is None:
                raise BakeError(f'"{ob.name}" has no faces to bake')
            self._bake_local[ob.name_full] = local
            if self.target == 'IMAGE_TEXTURES':
                self._check_images(ob, ob_eval, local)
            else:
                self._check_attribute(ob, local)

    def _check_images(self, ob, ob_eval, local):
        if local.uv is None:
            raise BakeError(f'"{ob.name}" has no UV map: add one (UV Editing) before baking '
                            f'into images')
        slots = [slot.material for slot in ob_eval.material_slots]
        if not slots:
            raise BakeError(f'"{ob.name}" has no material: add a material with an Image '
                            f'Texture node and make that node active')
        per_slot, problems, notes = [], [], []
        for material in slots:
            image, problem = active_image(material.original if material else None, notes)
            if image is None:
                per_slot.append(None)
                problems.append(problem)
                continue
            key = image.name_full
            if key not in self.images:
                self.images[key] = _image_target(image, ob.name)
            per_slot.append(self.images[key])
        if all(t is None for t in per_slot):
            raise BakeError(f'"{ob.name}": no active Image Texture node to bake into '
                            f'({"; ".join(problems)})')
        for problem in problems:
            if problem is not None:
                self.warn(f'"{ob.name}": faces of a slot are not baked ({problem})')
        for note in notes:
            self.warn(note)
        self._bake_slot_images[ob.name_full] = per_slot

    def _check_attribute(self, ob, local):
        mesh = ob.data
        if ob.mode == 'EDIT':
            raise BakeError(f'"{ob.name}" is in Edit Mode: leave it to bake color attributes')
        attribute = mesh.color_attributes.active_color
        if attribute is None:
            raise BakeError(f'"{ob.name}" has no color attribute: add one (Object Data ▸ '
                            f'Color Attributes) to bake into')
        if attribute.domain not in ('POINT', 'CORNER'):
            raise BakeError(f'color attribute "{attribute.name}" of "{ob.name}" is on the '
                            f'{attribute.domain.lower()} domain; use Vertex or Face Corner')
        if local.n_loops != len(mesh.loops) or len(local.co) != len(mesh.vertices):
            raise BakeError(f'the modifiers of "{ob.name}" change its topology ({len(local.co)} '
                            f'vertices evaluated, {len(mesh.vertices)} in the mesh): color '
                            f'attributes need the same vertices; apply or disable them')
        self._attr_target[ob.name_full] = AttributeTarget(
            ob.name, mesh, attribute.name, attribute.domain, local.n_loops, len(local.co),
            local.loop_vertex)

    # -- geometry --

    def _slot_emission(self, materials):
        out = []
        for material in materials:
            if material is None:
                out.append(None)
                continue
            key = material.original.name_full
            if key not in self._emission_cache:
                problems = []
                self._emission_cache[key] = material_emission(material.original, self.units,
                                                              problems)
                material_transparency(material.original, problems)
                for p in problems:
                    self.warn(p)
            out.append(self._emission_cache[key])
        return out

    def _slot_receivers(self, materials):
        out = []
        for material in materials:
            key = material.original.name_full if material is not None else None
            if key not in self._receiver_cache:
                problems = []
                self._receiver_cache[key] = material_receiver(
                    material.original if material is not None else None, problems)
                for p in problems:
                    self.warn(p)
            out.append(self._receiver_cache[key])
        return out

    def add_geometry(self, ob_eval, matrix, local, bake_name=None):
        M = np.array(matrix, dtype=np.float64)
        A = M[:3, :3]
        det = float(np.linalg.det(A))
        if not math.isfinite(det) or abs(det) < 1e-30:
            return  # scaled to nothing
        positions = _world_positions(local, M)
        shaded = local.loop_normal is not None  # a baked object's own read
        normals = None
        if shaded:
            normal_matrix = np.linalg.inv(A).T
            normals = local.loop_normal @ normal_matrix.T
            length = np.linalg.norm(normals, axis=1, keepdims=True)
            normals = np.where(length > 0, normals / np.where(length > 0, length, 1), 0)
        tri_vert, tri_loop = local.tri_vert, local.tri_loop
        if det < 0:  # mirrored: keep the winding counter-clockwise seen from the front
            tri_vert = tri_vert[:, [0, 2, 1]]
            tri_loop = tri_loop[:, [0, 2, 1]] if shaded else None

        materials = [slot.material for slot in ob_eval.material_slots]
        emissions = self._slot_emission(materials)
        if not ob_eval.visible_diffuse and any(e is not None for e in emissions):
            self.warn(f'"{ob_eval.name}" emits light but is invisible to diffuse rays; omis '
                      f'still lets it light the bake')
        slot_images = self._bake_slot_images.get(bake_name) if bake_name else None
        # The receiver closure matters only where omis shades: on baked objects.
        receivers = self._slot_receivers(materials) if bake_name else []

        # Group triangles by (emission, target image, receiver): each group is one omis mesh.
        n_slots = len(materials)
        slot_of_tri = (np.clip(local.material_index, 0, n_slots - 1) if n_slots
                       else np.zeros(len(tri_vert), np.int32))
        index, groups, slot_group = {}, [], []
        for s in range(max(n_slots, 1)):
            emission = emissions[s] if n_slots else None
            image = slot_images[s] if (slot_images and n_slots) else None
            receiver = receivers[s] if (receivers and n_slots) else None
            key = (emission, id(image), receiver)
            if key not in index:
                index[key] = len(groups)
                groups.append((emission, image, receiver))
            slot_group.append(index[key])
        group_of_tri = np.asarray(slot_group, np.int32)[slot_of_tri]

        attr = self._attr_target.get(bake_name) if bake_name else None
        self.counts["instances"] += 1
        for g, (emission, image, receiver) in enumerate(groups):
            select = group_of_tri == g
            count = int(select.sum())
            if count == 0:
                continue
            tris = tri_vert[select]
            loops = tri_loop[select] if shaded else None
            if len(groups) > 1:
                used, inverse = np.unique(tris, return_inverse=True)
                verts, tris = positions[used], inverse.reshape(-1, 3).astype(np.int32)
            else:
                verts = positions
            corner_normals = (_corner_normals(verts, tris, normals[loops.ravel()],
                                              local.flat[select]) if shaded else None)
            uvs = None
            baked = bake_name is not None and (image is not None or attr is not None)
            uv_area = 0.0
            if baked and image is not None:
                uvs = np.ascontiguousarray(local.uv[loops.ravel()], dtype=np.float32)
                uv_area = _uv_area(uvs)
            mesh_id = self.scene.add_mesh(np.ascontiguousarray(verts), tris, corner_normals,
                                          uvs, emission)
            if receiver is not None:
                self.scene.set_receiver(mesh_id, receiver[0], roughness=receiver[1])
                self.counts["receivers"][receiver[0]] = \
                    self.counts["receivers"].get(receiver[0], 0) + 1
            self.counts["meshes"] += 1
            self.counts["triangles"] += count
            self.counts["vertices"] += len(verts)
            if emission is not None:
                self.counts["emissive_meshes"] += 1
            if baked:
                part = Part(ob_eval.name, mesh_id, count, tri_loops=loops, uv_area=uv_area)
                (image.parts if image is not None else attr.parts).append(part)

    # -- lights --

    def _record(self, kind, light_id, **values):
        self.lights.append({"kind": kind, "id": light_id, **values})
        self.counts["lights"][kind] = self.counts["lights"].get(kind, 0) + 1

    def add_light(self, ob_eval, matrix):
        light = ob_eval.data
        name = ob_eval.name
        if light.cycles.is_portal:
            return
        if not ob_eval.visible_diffuse:
            self.warn(f'light "{name}" is invisible to diffuse rays: it does not light the bake')
            return
        if light.use_nodes:
            self.warn(f'light "{name}": its node tree is ignored (strength and colour come from '
                      f'the light settings)')
        u = self.units
        M = np.array(matrix, dtype=np.float64)
        position = M[:3, 3].copy()
        z = M[:3, 2]
        if not np.linalg.norm(z) > 0:
            return
        direction = -z / np.linalg.norm(z)   # lights point along their local -Z
        color, energy = tuple(light.color), float(light.energy)
        scene = self.scene
        if light.type == 'POINT':
            p = u.point_light(energy, color, light.shadow_soft_size)
            lid = scene.add_point_light(position, p.intensity, radius=p.radius)
            self._record("point", lid, position=position, intensity=p.intensity, radius=p.radius)
        elif light.type == 'SPOT':
            spot_size = _angle_upto_pi(light.spot_size)
            s = u.spot_light(energy, color, spot_size, light.spot_blend, light.shadow_soft_size)
            lid = scene.add_spot_light(position, direction, s.intensity, spot_size,
                                       spot_blend=light.spot_blend, radius=s.radius)
            self._record("spot", lid, position=position, direction=direction,
                         intensity=s.intensity, spot_size=spot_size,
                         spot_blend=light.spot_blend, radius=s.radius)
        elif light.type == 'SUN':
            s = u.sun_light(energy, color, light.angle)
            lid = scene.add_sun_light(direction, s.irradiance, angle=light.angle)
            self._record("sun", lid, direction=direction, irradiance=s.irradiance,
                         angle=light.angle)
        elif light.type == 'AREA':
            square = light.shape in ('SQUARE', 'DISK')
            eu = M[:3, 0] * light.size
            ev = M[:3, 1] * (light.size if square else light.size_y)
            su, sv = float(np.linalg.norm(eu)), float(np.linalg.norm(ev))
            if not (su > 0 and sv > 0):
                return
            round_shape = light.shape in ('DISK', 'ELLIPSE')
            spread = _angle_upto_pi(light.spread)
            a = u.area_light(energy, color, 'ELLIPSE' if round_shape else 'RECTANGLE', su, sv,
                             spread=spread)
            # omis emits toward cross(first, second); Blender toward local -Z. The
            # edges of a float32 world matrix are perpendicular only to ~1e-9; make
            # them exactly so (the omis core's spherical-rectangle sampler needs it).
            first, second = ev, eu - ev * (np.dot(eu, ev) / np.dot(ev, ev))
            second *= su / float(np.linalg.norm(second))
            if np.dot(np.cross(first, second), direction) < 0:
                first, second = second, first
            if round_shape:
                lid = scene.add_ellipse_light(position, 0.5 * first, 0.5 * second, a.radiance,
                                              two_sided=False, spread=spread)
                kind = "ellipse"
            else:
                corner = position - 0.5 * (first + second)
                lid = scene.add_rect_light(corner, first, second, a.radiance, two_sided=False,
                                           spread=spread)
                kind = "rect"
            self._record(kind, lid, center=position, axis_u=first, axis_v=second,
                         radiance=a.radiance, area=a.area, spread=spread,
                         shape=light.shape)
        else:
            return
        cycles = light.cycles
        if not cycles.cast_shadow or not cycles.use_multiple_importance_sampling:
            scene.set_light_flags(lid, cast_shadow=bool(cycles.cast_shadow),
                                  visible_to_bsdf=bool(cycles.use_multiple_importance_sampling))
            self.lights[-1].update(cast_shadow=bool(cycles.cast_shadow),
                                   visible_to_bsdf=bool(cycles.use_multiple_importance_sampling))

    def add_world(self, world):
        if world is None:
            return
        if not world.cycles_visibility.diffuse:
            return
        if not world.use_nodes or world.node_tree is None:
            color, strength = tuple(world.color), 1.0
        else:
            out = _active_output(world.node_tree, {'ShaderNodeOutputWorld'})
            if out is None:
                return
            node, _ = _linked_from(out.inputs['Surface'])
            while node is not None and node.type == 'REROUTE':
                node, _ = _linked_from(node.inputs[0])
            if node is None or node.mute:
                return
            if (node.type != 'BACKGROUND' or node.inputs['Color'].is_linked
                    or node.inputs['Strength'].is_linked):
                self.add_world_image(world)  # textures, skies, mixed backgrounds
                return
            color_in, strength_in = node.inputs['Color'], node.inputs['Strength']
            color, strength = _socket_value(color_in)[:3], _socket_value(strength_in)
        radiance = self.units.world_background(color, strength)
        if max(radiance) <= 0:
            return
        lid = self.scene.set_world(radiance)
        self.counts["world"] = True
        self._record("world", lid, radiance=radiance)

    def add_world_image(self, world):
        """A world that is not one constant Background, as Cycles evaluates it
        (world_map.py: rendered into an equirectangular map, cached)."""
        from . import world_map  # imports bpy
        rgb = world_map.world_map(world)
        if not rgb.any():
            return
        lid = self.scene.set_world_image(rgb)
        self.counts["world"] = True
        self._record("world", lid, image_shape=rgb.shape)

    # -- the whole scene --

    def run(self):
        context = self.context
        depsgraph = self.depsgraph = context.evaluated_depsgraph_get()
        visible = _render_visible_names(context.view_layer)
        self.check_bake_objects(depsgraph, visible)

        seen, baked = set(), set()
        for inst in depsgraph.object_instances:
            ob = inst.object
            original = ob.original
            if inst.is_instance:
                parent = inst.parent.original if inst.parent is not None else None
                if parent is not None and (parent.hide_render or parent.name_full not in visible):
                    continue
                if original.hide_render:
                    continue
            else:
                seen.add(original.name_full)
                if original.hide_render or original.name_full not in visible:
                    continue
                if ob.is_instancer and not original.show_instancer_for_render:
                    continue
            if ob.type == 'LIGHT':
                self.add_light(ob, inst.matrix_world)
                continue
            if ob.type not in _GEOMETRY_TYPES:
                continue
            bake_name = None
            if not inst.is_instance and original.name_full in self.bake_names:
                bake_name = original.name_full
                local = self._bake_local[bake_name]
                baked.add(bake_name)
            else:
                local = self._cached_local(inst, ob)
                if local is None:
                    continue
                if not ob.visible_shadow:
                    self.warn(f'"{ob.name}" has shadow visibility off; omis still lets it cast '
                              f'shadows')
            if not inst.is_instance:
                notes = _modifier_differences(original)
                if notes:
                    self.warn(f'"{original.name}": {"; ".join(notes)} — omis bakes the viewport '
                              f'evaluation')
            self.add_geometry(ob, inst.matrix_world, local, bake_name)

        for ob in self.bake_objects:
            if ob.name_full not in baked:
                raise BakeError(f'"{ob.name}" is hidden in the viewport: omis bakes the viewport '
                                f'evaluation, unhide it')
        missing = sorted(name for name in visible - seen
                         if (o := context.scene.objects.get(name)) is not None
                         and not o.hide_render and (o.type in _GEOMETRY_TYPES or o.type == 'LIGHT'))
        if missing:
            self.warn("hidden in the viewport but enabled for rendering, so missing from the "
                      "omis bake: " + ", ".join(f'"{n}"' for n in missing[:8])
                      + (" …" if len(missing) > 8 else ""))

        self.add_world(context.scene.world)
        mesh_cache.forget_unused(depsgraph, self._shared_used)

        has_light = bool(self.lights) or self.counts["emissive_meshes"] > 0
        if not has_light:
            self.warn("the scene has no lights (no lamps, emissive meshes or world): the "
                      "result is black")
        images = [t for t in self.images.values() if t.parts]
        return Export(self.scene, images, list(self._attr_target.values()), self.warnings,
                      self.counts, self.lights, has_light)

    def _cached_local(self, inst, ob):
        cacheable = not (inst.is_instance and inst.parent is not None
                         and inst.parent.original == ob.original)
        key = (ob.original.name_full, ob.data.name_full if ob.data is not None else "")
        if cacheable and key in self._mesh_cache:
            return self._mesh_cache[key]
        if not cacheable:
            return _to_local_mesh(ob, baked=False)
        local = mesh_cache.read(self.depsgraph, ob, _read_shared_mesh, self._shared_used)
        self._mesh_cache[key] = local
        return local


def export_scene(context, objects, target, *, omis, units):
    """Exports the view layer for baking `objects` (original mesh objects) into `target`.

    Raises BakeError for anything that makes the bake impossible; returns an
    Export whose scene is built but not yet committed.
    """
    return _Exporter(context, omis, units, list(objects), target).run()
