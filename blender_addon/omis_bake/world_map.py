"""A Blender world as omis sees it: an equirectangular radiance map evaluated by Cycles.

Any world that is not one constant Background (an Environment Texture with its
Mapping and Strength, a Sky Texture, mixed Backgrounds, any node tree) is
rendered alone by Cycles through an equirectangular panoramic camera turned so
that its pixels are Cycles' own equirectangular texels (rotation (π/2, 0, −π/2):
pixel (u, v) looks along u = 0.5 − atan2(y, x)/2π, v = 1 − acos(z)/π, the
Environment Texture's convention; checked against Blender in
tests/blender/test_world_map.py). A box pixel filter one pixel wide makes each
pixel the mean radiance over its own footprint, so the map's integral is the
world's: a small sun keeps its power whatever the resolution.

Maps are cached per world state (a fingerprint of the node tree: every node's
settings, inputs, links, images and groups): a second bake of an unchanged
world renders nothing.
"""

import math
import os
import tempfile

import bpy
import numpy as np

# Width of the map when the world asks for none (Cycles: Map Resolution 0 and no
# environment image) and its least width: 2048 texels across make a texel 0.18°,
# so a 0.5° sun spans ~3 texels. (4096 × 2048 at 16 samples took 158 s for a
# Nishita sky on a loaded 2-core machine; 2048 × 1024 at 4 samples is 1/16 of it.)
DEFAULT_WIDTH = 2048
MIN_WIDTH = 2048
SAMPLES = 4  # per pixel (stratified): exact inside features, noisy only on their edges

_cache = {}  # fingerprint -> read-only (H, W, 3) float32 array, rows top first
_CACHE_SIZE = 2

_SKIPPED = {"rna_type", "name", "label", "location", "width", "width_hidden", "height",
            "dimensions", "select", "show_options", "show_preview", "hide", "show_texture",
            "color", "use_custom_color", "parent", "internal_links", "inputs", "outputs",
            "bl_idname", "bl_label", "bl_description", "bl_icon", "bl_static_type",
            "bl_width_default", "bl_width_min", "bl_width_max", "bl_height_default",
            "bl_height_min", "bl_height_max", "type"}


def _value(v):
    if isinstance(v, bpy.types.Image):
        return ("image", v.name_full, v.filepath_raw, v.source, tuple(v.size), v.is_dirty,
                v.colorspace_settings.name, getattr(v, "alpha_mode", None))
    if isinstance(v, bpy.types.ID):
        return ("id", v.name_full)
    if hasattr(v, "__len__") and not isinstance(v, str):
        try:
            return tuple(_value(x) for x in v)
        except TypeError:
            return repr(v)
    if isinstance(v, (bool, int, float, str)) or v is None:
        return v
    return repr(v)


def _tree_fingerprint(tree, seen):
    if tree is None or tree.name_full in seen:
        return None
    seen.add(tree.name_full)
    nodes = []
    for node in sorted(tree.nodes, key=lambda n: n.name):
        props = []
        for p in node.bl_rna.properties:
            if p.identifier in _SKIPPED:
                continue
            value = getattr(node, p.identifier, None)
            props.append((p.identifier, _value(value)))
            if p.identifier == "node_tree":
                props.append(("group", _tree_fingerprint(value, seen)))
            if p.identifier == "image_user" and value is not None:
                props.append(("frame", value.frame_current, value.frame_offset))
        inputs = [(s.identifier, _value(getattr(s, "default_value", None))) for s in node.inputs]
        nodes.append((node.bl_idname, node.name, node.mute, tuple(props), tuple(inputs)))
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name,
                    l.to_socket.identifier, l.is_muted) for l in tree.links)
    return tuple(nodes), tuple(links)


def map_size(world):
    """(width, height): Cycles' Map Resolution (or the environment image's width when
    it is 0), never below MIN_WIDTH; height = width / 2."""
    width = int(getattr(world.cycles, "sample_map_resolution", 0) or 0)
    if width <= 0 and world.use_nodes and world.node_tree is not None:
        for node in world.node_tree.nodes:
            if node.type == 'TEX_ENVIRONMENT' and node.image is not None and node.image.size[0]:
                width = max(width, int(node.image.size[0]))
    width = max(width or DEFAULT_WIDTH, MIN_WIDTH)
    width += width % 2
    return width, width // 2


def fingerprint(world):
    """Everything of a world that its rendered map depends on."""
    return (world.name_full, world.use_nodes, tuple(world.color), map_size(world), SAMPLES,
            _tree_fingerprint(world.node_tree, set()) if world.use_nodes else None)


def world_map(world):
    """The world's radiance as an (H, W, 3) float32 array, rows top first (cached)."""
    key = fingerprint(world)
    if key in _cache:
        return _cache[key]
    rgb = render_world(world, *map_size(world))
    rgb.flags.writeable = False
    while len(_cache) >= _CACHE_SIZE:
        _cache.pop(next(iter(_cache)))
    _cache[key] = rgb
    return rgb


def clear():
    _cache.clear()


def render_world(world, width, height, samples=SAMPLES):
    """Cycles renders the world alone into an equirectangular EXR; its pixels come
    back as radiance, rows top first. Everything made here is removed again, and
    the world's camera visibility (which the render needs) is restored."""
    scene = bpy.data.scenes.new("omis world map")
    camera_data = bpy.data.cameras.new("omis world map")
    camera = bpy.data.objects.new("omis world map", camera_data)
    visible_to_camera = world.cycles_visibility.camera
    fd, path = tempfile.mkstemp(suffix=".exr", prefix="omis_world_")
    os.close(fd)
    image = None
    try:
        world.cycles_visibility.camera = True
        scene.world = world
        scene.render.engine = 'CYCLES'
        cycles = scene.cycles
        cycles.device = 'CPU'
        cycles.samples = samples
        cycles.use_denoising = False
        cycles.use_adaptive_sampling = False
        cycles.pixel_filter_type = 'BOX'  # a pixel is the mean over its own footprint
        cycles.filter_width = 1.0
        cycles.seed = 0
        scene.render.resolution_x, scene.render.resolution_y = width, height
        scene.render.resolution_percentage = 100
        scene.render.film_transparent = False
        scene.render.use_compositing = False
        scene.render.use_sequencer = False
        camera_data.type = 'PANO'
        camera_data.cycles.panorama_type = 'EQUIRECTANGULAR'
        camera.rotation_euler = (math.pi / 2, 0.0, -math.pi / 2)
        scene.collection.objects.link(camera)
        scene.camera = camera
        settings = scene.render.image_settings
        settings.file_format = 'OPEN_EXR'
        settings.color_depth = '32'
        settings.color_mode = 'RGB'
        scene.render.filepath = path
        bpy.ops.render.render(write_still=True, scene=scene.name)
        image = bpy.data.images.load(path, check_existing=False)
        pixels = np.empty(width * height * image.channels, np.float32)
        image.pixels.foreach_get(pixels)
        rgb = pixels.reshape(height, width, image.channels)[::-1, :, :3]
        return np.ascontiguousarray(np.maximum(rgb, 0.0))
    finally:
        world.cycles_visibility.camera = visible_to_camera
        if image is not None:
            bpy.data.images.remove(image)
        bpy.data.objects.remove(camera)
        bpy.data.cameras.remove(camera_data)
        bpy.data.scenes.remove(scene)
        try:
            os.remove(path)
        except OSError:
            pass
