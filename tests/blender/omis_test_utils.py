"""Functions shared by the headless Blender tests (run through scripts/blender_run.sh)."""

import importlib.util
import math
import os
import sys
import tempfile
import time

import bpy
import numpy as np

RESULTS = []


def args():
    """The script's own arguments (after Blender's `--`, and a second `--` if any)."""
    argv = sys.argv
    rest = argv[argv.index("--") + 1:] if "--" in argv else []
    return rest[1:] if rest[:1] == ["--"] else rest


def log(text=""):
    """A line of a long run's report, shown at once."""
    print(text, flush=True)


def check(condition, message):
    if not condition:
        raise AssertionError(message)


def unexpected_warnings(stats):
    """A bake's warnings other than its buried-texel lines (texels inside other
    objects: reported as warnings, checked on their own by the tests that expect them)."""
    from omis_bake import job
    buried = set(job.buried_report(stats.get("buried_texels", {}), stats.get("target")))
    return [w for w in stats["warnings"] if w not in buried]


def reset_scene(engine='CYCLES'):
    """An empty scene (the add-on stays registered, unlike read_factory_settings)."""
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.lights, bpy.data.materials,
                       bpy.data.images, bpy.data.cameras, bpy.data.collections):
        for item in list(collection):
            collection.remove(item)
    scene = bpy.context.scene
    scene.world = None
    scene.render.engine = engine
    # The margin these tests check is Extend; Adjacent Faces (Blender 3.4's
    # default) has tests of its own (test_adjacent_margin.py).
    scene.render.bake.margin_type = 'EXTEND'
    scene.render.bake.use_selected_to_active = False
    c = scene.cycles
    c.device = 'CPU'
    c.use_denoising = False
    c.use_adaptive_sampling = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.seed = 0
    return scene


def link(ob):
    bpy.context.scene.collection.objects.link(ob)
    return ob


def make_image(name, size=64, float_buffer=True, color=(0.0, 0.0, 0.0, 1.0)):
    img = bpy.data.images.new(name, size, size, float_buffer=float_buffer, alpha=True)
    img.generated_color = color
    return img


def emission_material(name, color=(1.0, 1.0, 1.0), strength=1.0):
    """A material whose surface is one Emission node (no BSDF): an emitter as an
    artist makes one, for Cycles' emission sampling and omis' mesh lights."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    em = nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (*color, 1.0)
    em.inputs["Strength"].default_value = strength
    mat.node_tree.links.new(em.outputs[0], nodes["Material Output"].inputs["Surface"])
    return mat


def constant_world(name="World", color=None, strength=1.0):
    """A node world of one constant Background (colour, strength), made the scene's."""
    world = bpy.data.worlds.new(name)
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    if color is not None:
        background.inputs["Color"].default_value = (*color, 1.0)
    background.inputs["Strength"].default_value = strength
    bpy.context.scene.world = world
    return world


def sky_image(name="sky", width=512, sun_elevation=35.0, sun_azimuth=-20.0, sun_diameter=3.0,
              sun_radiance=2000.0):
    """omis.demo.sky (a procedural HDR sky with a small, very bright sun toward
    (elevation, azimuth) in degrees) as a float Blender image, rows bottom first."""
    import numpy as np
    from omis import demo
    height = width // 2
    rgb = demo.sky(width, height, sun_elevation, sun_azimuth, sun_diameter, sun_radiance)[0][::-1]
    img = bpy.data.images.new(name, width, height, float_buffer=True, alpha=True)
    rgba = np.concatenate([rgb, np.ones((height, width, 1))], axis=-1).astype(np.float32)
    img.pixels.foreach_set(rgba.ravel())
    img.pack()
    return img


def image_world(image, strength=1.0, rotation=None, mix_constant=None, name="World"):
    """A world of an Environment Texture (optionally through a Mapping node's
    rotation, optionally added to a constant Background), made the scene's."""
    world = bpy.data.worlds.new(name)
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    background = nodes["Background"]
    background.inputs["Strength"].default_value = strength
    env = nodes.new("ShaderNodeTexEnvironment")
    env.image = image
    links.new(env.outputs["Color"], background.inputs["Color"])
    if rotation is not None:
        coords = nodes.new("ShaderNodeTexCoord")
        mapping = nodes.new("ShaderNodeMapping")
        mapping.inputs["Rotation"].default_value = rotation
        links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
        links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    if mix_constant is not None:
        color, constant_strength = mix_constant
        constant = nodes.new("ShaderNodeBackground")
        constant.inputs["Color"].default_value = (*color, 1.0)
        constant.inputs["Strength"].default_value = constant_strength
        add = nodes.new("ShaderNodeAddShader")
        links.new(background.outputs[0], add.inputs[0])
        links.new(constant.outputs[0], add.inputs[1])
        links.new(add.outputs[0], nodes["World Output"].inputs["Surface"])
    bpy.context.scene.world = world
    return world


def image_material(name, image):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    node = mat.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    mat.node_tree.nodes.active = node
    return mat


def grid_mesh(name, size=2.0, cuts=1, location=(0, 0, 0), uv_rect=(0, 0, 1, 1)):
    """A square of side `size` in the XY plane facing +Z, UVs spanning uv_rect."""
    n = cuts + 1
    xs = np.linspace(-size / 2, size / 2, n + 1)
    verts = [(x, y, 0.0) for y in xs for x in xs]
    faces = [(j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1,
              (j + 1) * (n + 1) + i) for j in range(n) for i in range(n)]
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    uv = me.uv_layers.new(name="UVMap")
    u0, v0, u1, v1 = uv_rect
    co = np.array(verts)
    for loop in me.loops:
        x, y, _ = co[loop.vertex_index]
        uv.data[loop.index].uv = (u0 + (u1 - u0) * (x / size + 0.5),
                                  v0 + (v1 - v0) * (y / size + 0.5))
    ob = link(bpy.data.objects.new(name, me))
    ob.location = location
    return ob


def image_grid(name, image, material="m", **grid):
    """grid_mesh(name, **grid) whose material bakes into `image`."""
    ob = grid_mesh(name, **grid)
    ob.data.materials.append(image_material(material, image))
    return ob


def add_light(kind, name=None, energy=100.0, location=(0, 0, 1), rotation=(0, 0, 0), **props):
    data = bpy.data.lights.new(name or kind.lower(), kind)
    data.energy = energy
    for key, value in props.items():
        setattr(data, key, value)
    ob = link(bpy.data.objects.new(name or kind.lower(), data))
    ob.location = location
    ob.rotation_euler = rotation
    return ob


def add_box(name, size, location):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=location)
    ob = bpy.context.active_object
    ob.name = name
    ob.scale = size
    return ob


def select_only(objects):
    for ob in bpy.context.view_layer.objects:
        ob.select_set(False)
    for ob in objects:
        ob.select_set(True)
    if objects:
        bpy.context.view_layer.objects.active = objects[0]


def pixels(image):
    w, h = image.size
    px = np.empty(w * h * image.channels, np.float32)
    image.pixels.foreach_get(px)
    return px.reshape(h, w, image.channels)


def set_pixels(image, value):
    px = np.empty(image.size[0] * image.size[1] * image.channels, np.float32)
    px[:] = np.tile(np.asarray(value, np.float32), image.size[0] * image.size[1])
    image.pixels.foreach_set(px)


def cycles_bake(objects, samples, seed):
    """Cycles' Diffuse bake, Direct only, no Color: E_direct/π into the active images."""
    scene = bpy.context.scene
    scene.cycles.samples = samples
    scene.cycles.seed = seed
    select_only(objects)
    start = time.perf_counter()
    result = bpy.ops.object.bake(type='DIFFUSE', pass_filter={'DIRECT'}, margin=0,
                                 use_clear=True, target='IMAGE_TEXTURES', save_mode='INTERNAL',
                                 use_selected_to_active=False)
    check(result == {'FINISHED'}, f"Cycles bake failed: {result}")
    return time.perf_counter() - start


def box_mean(values, weights, radius):
    """Mean of values over a (2r+1)² window, weighted (0/1) — separable cumulative sums."""
    def box(a):
        k = 2 * radius + 1
        p = np.pad(a, radius, mode='constant')
        c = np.cumsum(np.cumsum(p, axis=0), axis=1)
        c = np.pad(c, ((1, 0), (1, 0)))
        return c[k:, k:] - c[:-k, k:] - c[k:, :-k] + c[:-k, :-k]
    num, den = box(values * weights), box(weights.astype(np.float64))
    return np.where(den > 0, num / np.maximum(den, 1), 0)


def compare_to_cycles(label, omis_value, omis_noise, omis_mask, cycles_a, cycles_b,
                      tolerance_sigma=4.0, min_pass=0.99, max_bias=0.01):
    """Per covered interior texel: |omis − cycles| ≤ 4σ + δ, with σ² the two noise
    variances and δ half the largest step to a neighbour (Cycles box-filters each
    texel, omis samples its centre; the two differ by up to that much at a shadow
    edge). Aggregate relative bias < 1 %. Values: grey = mean of RGB."""
    o = omis_value.astype(np.float64).mean(axis=2)
    a = cycles_a[..., :3].astype(np.float64).mean(axis=2)
    b = cycles_b[..., :3].astype(np.float64).mean(axis=2)
    c = 0.5 * (a + b)
    mask = omis_mask > 0.5
    interior = mask.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            interior &= np.roll(np.roll(mask, dy, 0), dx, 1)
    interior[0, :] = interior[-1, :] = interior[:, 0] = interior[:, -1] = False
    # Variance of the mean c; differences of cumulative sums can round below 0
    # where a whole window is black (NaN under the square root otherwise).
    var_c = np.maximum(box_mean(0.25 * (a - b) ** 2, interior, 3), 0.0)
    var_o = (omis_noise.astype(np.float64) * o) ** 2
    sigma = np.sqrt(var_c + var_o)
    step = np.zeros_like(o)
    for axis in (0, 1):
        for shift in (-1, 1):
            step = np.maximum(step, np.abs(np.roll(o, shift, axis) - o))
    delta = 0.5 * step
    err = np.abs(o - c)
    ok = err <= tolerance_sigma * sigma + delta
    n = int(interior.sum())
    check(n > 100, f"{label}: only {n} interior texels")
    passed = float(ok[interior].mean())
    bias = float((o[interior].sum() - c[interior].sum()) / c[interior].sum())
    # Diagnostic only: ≈ 1 where the lighting is smooth at texel scale; edges
    # (where the two texel filters differ) push it up.
    z2 = float(np.median(((o - c) / np.maximum(sigma, 1e-12))[interior] ** 2) / 0.4549)
    row = {"scene": label, "texels": n, "pass_fraction": passed, "relative_bias": bias,
           "median_z2_scaled": z2, "omis_rel_noise": float(np.median(omis_noise[interior])),
           "cycles_rel_noise": float(np.median(np.sqrt(var_c[interior]) /
                                               np.maximum(c[interior], 1e-12))),
           "mean_value": float(c[interior].mean())}
    RESULTS.append(row)
    print(f"AGREEMENT {label}: texels {n}, within 4σ+δ {100 * passed:.2f} %, "
          f"relative bias {100 * bias:+.3f} %, median z²/0.455 {z2:.2f}, "
          f"median rel. noise omis {100 * row['omis_rel_noise']:.2f} % / Cycles "
          f"{100 * row['cycles_rel_noise']:.2f} %, mean value {row['mean_value']:.4f}")
    worst = np.argsort(-(err - tolerance_sigma * sigma - delta)[interior])[:5]
    if passed < min_pass or abs(bias) >= max_bias:
        ys, xs = np.nonzero(interior)
        for i in worst:
            y, x = ys[i], xs[i]
            print(f"  texel ({x},{y}): omis {o[y, x]:.5f} cycles {c[y, x]:.5f} "
                  f"(a {a[y, x]:.5f} b {b[y, x]:.5f}) σ {sigma[y, x]:.5f} δ {delta[y, x]:.5f}")
    check(passed >= min_pass, f"{label}: only {100 * passed:.2f} % of texels agree with Cycles")
    check(abs(bias) < max_bias, f"{label}: aggregate relative bias {100 * bias:+.3f} % ≥ 1 %")
    return row


def ignored_settings_scene():
    """A floor whose material has a normal-map texture, a textured Metallic and the bake
    target (unlinked) with the BSDF the active node; a lamp with a node tree; a
    half-transparent occluder. Returns (floor, target image, normal-map image)."""
    reset_scene()
    target = make_image("target", 32)
    normal_img = make_image("normal_tex", 32, color=(0.5, 0.5, 1.0, 1.0))
    mat = bpy.data.materials.new("Floor")
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    normal_tex = nodes.new("ShaderNodeTexImage")
    normal_tex.name = "Normal Texture"
    normal_tex.image = normal_img
    normal_map = nodes.new("ShaderNodeNormalMap")
    links.new(normal_tex.outputs["Color"], normal_map.inputs["Color"])
    links.new(normal_map.outputs["Normal"], bsdf.inputs["Normal"])
    noise = nodes.new("ShaderNodeTexNoise")
    links.new(noise.outputs["Fac"], bsdf.inputs["Metallic"])
    bake_node = nodes.new("ShaderNodeTexImage")
    bake_node.name = "Bake Target"
    bake_node.image = target
    nodes.active = bsdf
    floor = grid_mesh("Floor", size=2.0, cuts=1)
    floor.data.materials.append(mat)
    lamp = add_light('AREA', "lamp", energy=200.0, location=(0.2, 0.1, 1.5), size=0.5)
    lamp.data.use_nodes = True
    glass = bpy.data.materials.new("HalfGlass")
    glass.use_nodes = True
    glass.node_tree.nodes["Principled BSDF"].inputs["Alpha"].default_value = 0.5
    box = add_box("Box", (0.3, 0.3, 0.3), (0.5, 0.5, 0.4))
    box.data.materials.append(glass)
    select_only([floor])
    return floor, target, normal_img


def temp_dir():
    return tempfile.mkdtemp(prefix="omis_blender_test_")


def deg(x):
    return math.radians(x)


def report_time(name, start):
    print(f"TIME {name}: {time.perf_counter() - start:.2f} s")


class FakeLayout:
    """Records what a panel draws (Blender cannot draw panels in background mode)."""

    def __init__(self, log):
        self.log = log

    def __getattr__(self, name):
        if name in ("row", "column", "box", "grid_flow", "split"):
            return lambda *a, **k: FakeLayout(self.log)
        if name == "label":
            return lambda text="", **k: self.log.append(("label", text))
        if name == "prop":
            return lambda data, prop, **k: self.log.append(("prop", prop))
        if name == "operator":
            return lambda idname, **k: self.log.append(("operator", idname)) or FakeLayout(self.log)
        raise AttributeError(name)

    def __setattr__(self, name, value):
        if name == "log":
            object.__setattr__(self, name, value)


def stacked(arrays):
    """Several images' arrays (a lightmap per object) as one: stacked rows, each
    framed by a row and column of zeros so that no texel counts another image's
    as a neighbour (interior_texels, compare_to_cycles). Trailing dimensions
    (channels) are kept."""
    width = max(a.shape[1] for a in arrays) + 2
    framed = []
    for a in arrays:
        f = np.zeros((a.shape[0] + 2, width) + a.shape[2:], a.dtype)
        f[1:-1, 1:a.shape[1] + 1] = a
        framed.append(f)
    return np.concatenate(framed, axis=0)


def interior_texels(mask):
    """The texels of `mask` whose 8 neighbours are in it too (and not on the
    image's rim): the benches compare these, away from the bake's margins."""
    m = mask.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            m &= np.roll(np.roll(mask, dy, 0), dx, 1)
    m[0, :] = m[-1, :] = m[:, 0] = m[:, -1] = False
    return m


def demo_room(size):
    """The demo room of scripts/blender_demo.py, built into the current scene;
    returns the objects to bake (its floor)."""
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    spec = importlib.util.spec_from_file_location(
        "blender_demo", os.path.join(root, "scripts", "blender_demo.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    floor, _ = module.build_demo(size)
    return [floor]
