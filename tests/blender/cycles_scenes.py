"""The scenes of the Cycles-agreement test (every light type, occluders, two
objects sharing an image, emission and a world, interpenetrating objects with a
lightmap each), shared with the equal-time
benchmark (bench/bench_cycles.py). Each builder adds its objects to the current
(reset) scene and returns the objects to bake, into one image of `size`² texels
or (issue 32's scenes) an image per object.
"""

import bpy

import omis_test_utils as U

SIZE = 64


def receiver(image, name="Receiver", **kwargs):
    return U.image_grid(name, image, material=name + "Mat", **kwargs)


def scene_area(size=SIZE):
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    U.add_light('AREA', "square", energy=60.0, location=(-0.5, -0.2, 0.8),
                rotation=(0, U.deg(20), 0), shape='SQUARE', size=0.5)
    U.add_light('AREA', "rect_spread", energy=120.0, location=(0.5, 0.3, 0.6),
                rotation=(U.deg(-15), 0, U.deg(30)), shape='RECTANGLE', size=0.8, size_y=0.3,
                spread=U.deg(90))
    return objs


def scene_area_round(size=SIZE):
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    U.add_light('AREA', "disk_spread", energy=80.0, location=(0.0, -0.4, 0.7),
                rotation=(U.deg(25), 0, 0), shape='DISK', size=0.6, spread=U.deg(120))
    U.add_light('AREA', "ellipse", energy=60.0, location=(0.3, 0.5, 0.5),
                rotation=(0, U.deg(-20), U.deg(40)), shape='ELLIPSE', size=0.6, size_y=0.3)
    return objs


def _spot(name, radius):
    """The spot light point_spot and spot_radius share (a 60° cone, tilted)."""
    U.add_light('SPOT', name, energy=400.0, location=(0.4, 0.3, 1.2),
                rotation=(U.deg(15), U.deg(-10), 0), spot_size=U.deg(60), spot_blend=0.3,
                shadow_soft_size=radius)


def scene_point_spot(size=SIZE):
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    U.add_light('POINT', "point_radius", energy=150.0, location=(-0.5, -0.5, 1.0),
                shadow_soft_size=0.2)
    _spot("spot", radius=0.0)
    return objs


def scene_spot_radius(size=SIZE):
    # Cycles 3.4 applies the spot cone to each sampled point of the light's disk
    # (direction -ls->D); omis uses the cone at the light's centre. Fails until
    # the core follows Cycles (the ctest entry is disabled meanwhile).
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    _spot("spot_radius", radius=0.1)
    return objs


def scene_sun_occluder(size=SIZE):
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    U.add_light('SUN', "sun", energy=3.0, rotation=(U.deg(30), U.deg(10), 0),
                angle=U.deg(10))
    U.add_light('POINT', "point_delta", energy=60.0, location=(0.6, -0.6, 0.9),
                shadow_soft_size=0.0)
    U.add_box("occluder", (0.6, 0.5, 0.1), (0.0, 0.1, 0.5))
    return objs


def scene_shared_image(size=SIZE):
    img = U.make_image("shared", size)
    mat = U.image_material("SharedMat", img)
    left = U.grid_mesh("Left", size=1.0, cuts=1, location=(-0.55, 0, 0),
                       uv_rect=(0.0, 0.0, 0.5, 1.0))
    left.scale = (1.0, 2.0, 1.0)
    right = U.grid_mesh("Right", size=1.0, cuts=1, location=(0.55, 0, 0.1),
                        uv_rect=(0.5, 0.0, 1.0, 1.0))
    right.scale = (1.0, 2.0, 1.0)
    right.rotation_euler = (0, U.deg(-15), 0)
    for ob in (left, right):
        ob.data.materials.append(mat)
    U.add_light('AREA', "square", energy=150.0, location=(0.0, 0.0, 1.0), shape='SQUARE',
                size=0.7)
    U.add_light('POINT', "point", energy=80.0, location=(0.8, 0.7, 0.8), shadow_soft_size=0.1)
    U.add_box("occluder", (0.3, 0.3, 0.3), (-0.2, -0.3, 0.45))
    return [left, right]


def scene_emission_world(size=SIZE):
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    bpy.ops.mesh.primitive_plane_add(size=0.6, location=(0.2, 0.0, 0.7),
                                     rotation=(U.deg(180), 0, 0))
    emitter = bpy.context.active_object
    emitter.name = "emitter"
    emitter.data.materials.append(U.emission_material("Glow", (1.0, 0.8, 0.6), 6.0))
    U.add_box("occluder", (0.4, 0.4, 0.05), (-0.4, 0.0, 0.35))
    U.constant_world(color=(0.3, 0.4, 0.5), strength=0.5)
    return objs


def _principled_receiver(image, roughness, name="Receiver"):
    """A grid whose material is the default Principled BSDF at `roughness`."""
    ob = receiver(image, name, size=2.0, cuts=2)
    bsdf = ob.data.materials[0].node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Roughness"].default_value = roughness
    return ob


def scene_principled_r0(size=SIZE):
    # Grazing suns (issue 12): Principled diffuse is not Lambert there.
    img = U.make_image("bake", size)
    objs = [_principled_receiver(img, 0.0)]
    U.add_light('SUN', "sun79", energy=3.0, rotation=(U.deg(79), 0, U.deg(20)),
                angle=U.deg(4))
    return objs


def scene_principled_r05(size=SIZE):
    img = U.make_image("bake", size)
    objs = [_principled_receiver(img, 0.5)]
    U.add_light('SUN', "sun60", energy=2.0, rotation=(U.deg(60), 0, U.deg(-30)),
                angle=U.deg(6))
    U.add_light('SUN', "sun85_delta", energy=4.0, rotation=(U.deg(85), 0, U.deg(120)),
                angle=0.0)
    return objs


def scene_principled_r1(size=SIZE):
    img = U.make_image("bake", size)
    objs = [_principled_receiver(img, 1.0)]
    U.add_light('SUN', "sun79", energy=3.0, rotation=(U.deg(79), 0, U.deg(200)),
                angle=U.deg(4))
    U.add_light('AREA', "low_area", energy=150.0, location=(1.6, 0.0, 0.25),
                rotation=(0, U.deg(-80), 0), shape='SQUARE', size=0.5)
    return objs


def scene_oren_nayar(size=SIZE):
    # Diffuse BSDF with roughness: Cycles' Oren–Nayar, viewed along the normal.
    img = U.make_image("bake", size)
    ob = receiver(img, size=2.0, cuts=2)
    tree = ob.data.materials[0].node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Roughness"].default_value = 0.8
    tree.links.new(diffuse.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    U.add_light('SUN', "sun70", energy=3.0, rotation=(U.deg(70), 0, U.deg(45)),
                angle=U.deg(5))
    return [ob]


def scene_touching_walls():
    """Vertex colours where objects meet (issue 12): a 6 × 6-quad floor (49
    vertices), two walls standing on two of its edges and a box resting on it
    whose sides pass through a row of its vertices; a sun from the open side and
    a square area light. Returns the floor (it carries a POINT colour attribute)."""
    floor = U.grid_mesh("Floor", size=2.0, cuts=5)
    floor.data.materials.append(bpy.data.materials.new("FloorMat"))
    floor.data.color_attributes.new("baked", 'FLOAT_COLOR', 'POINT')
    floor.data.color_attributes.active_color = floor.data.color_attributes["baked"]
    for name, location, rotation in (("WallW", (-1.0, 0.0, 0.5), (0, U.deg(90), 0)),
                                     ("WallN", (0.0, 1.0, 0.5), (U.deg(90), 0, 0))):
        bpy.ops.mesh.primitive_plane_add(size=1.0, location=location, rotation=rotation)
        wall = bpy.context.active_object
        wall.name = name
        wall.scale = (1.0, 2.0, 1.0) if name == "WallW" else (2.0, 1.0, 1.0)
    # Box: x ∈ [0, 1/3], y ∈ [−1/3, 1/3], z ∈ [0, 0.4]: its sides meet floor vertices.
    U.add_box("Box", (1.0 / 3.0, 2.0 / 3.0, 0.4), (1.0 / 6.0, 0.0, 0.2))
    U.add_light('SUN', "sun", energy=2.0, rotation=(U.deg(40), U.deg(-30), U.deg(-20)),
                angle=U.deg(3))
    U.add_light('AREA', "square", energy=120.0, location=(0.3, -0.3, 1.2),
                rotation=(U.deg(10), 0, 0), shape='SQUARE', size=0.6)
    return [floor]


def scene_suzanne_vertices():
    """Vertex colours on Suzanne (flat-shaded, many non-planar quads, concave
    corners) standing on a floor, under a sun and an area light. Returns
    Suzanne (it carries a POINT colour attribute)."""
    bpy.ops.mesh.primitive_monkey_add(size=1.0, location=(0, 0, 0.5))
    monkey = bpy.context.active_object
    monkey.name = "Suzanne"
    monkey.data.materials.append(bpy.data.materials.new("SuzanneMat"))
    monkey.data.color_attributes.new("baked", 'FLOAT_COLOR', 'POINT')
    monkey.data.color_attributes.active_color = monkey.data.color_attributes["baked"]
    U.grid_mesh("Floor", size=4.0, cuts=1)
    U.add_light('SUN', "sun", energy=2.0, rotation=(U.deg(40), U.deg(-30), U.deg(-20)),
                angle=U.deg(3))
    U.add_light('AREA', "square", energy=120.0, location=(0.3, -1.3, 1.8),
                rotation=(U.deg(30), 0, 0), shape='SQUARE', size=0.6)
    return [monkey]


def scene_many_lights(size=SIZE):
    # Issue 8: 64 lights of mixed types (squares, disks, points with and without
    # radius, spots) in an 8 × 8 grid over the receiver, and a box shadowing it:
    # the effect plan's light tree and its drawn delta lights against Cycles.
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    kinds = ('SQUARE', 'DISK', 'POINT', 'POINT_DELTA', 'SPOT')
    for j in range(8):
        for i in range(8):
            k = (i + 3 * j) % len(kinds)
            x, y = -0.9 + i * (1.8 / 7), -0.9 + j * (1.8 / 7)
            z = 0.5 + 0.08 * ((i * 5 + j * 3) % 7)
            name = f"l{j}{i}"
            color = (1.0, 0.6 + 0.05 * i, 0.4 + 0.07 * j)
            if kinds[k] in ('SQUARE', 'DISK'):
                U.add_light('AREA', name, energy=3.0 + (i + j) % 4, location=(x, y, z),
                            rotation=(U.deg(10 * (i - 4)), U.deg(8 * (j - 4)), 0),
                            shape=kinds[k], size=0.15, color=color)
            elif kinds[k] == 'SPOT':
                U.add_light('SPOT', name, energy=6.0, location=(x, y, z),
                            rotation=(U.deg(12), 0, 0), spot_size=U.deg(70),
                            spot_blend=0.2, shadow_soft_size=0.0, color=color)
            else:
                U.add_light('POINT', name, energy=2.0, location=(x, y, z), color=color,
                            shadow_soft_size=0.05 if kinds[k] == 'POINT' else 0.0)
    U.add_box("occluder", (0.5, 0.3, 0.05), (0.1, -0.1, 0.3))
    return objs


def scene_emissive_mesh(size=SIZE):
    # Issue 8: an emissive UV sphere of 16,256 triangles (128 × 64) above the
    # receiver, its lower half shading part of it from a small square light.
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    bpy.ops.mesh.primitive_uv_sphere_add(segments=128, ring_count=64, radius=0.3,
                                         location=(0.2, 0.1, 0.6))
    sphere = bpy.context.active_object
    sphere.name = "glow_sphere"
    sphere.data.materials.append(U.emission_material("Glow", (1.0, 0.85, 0.7), 3.0))
    U.add_light('AREA', "square", energy=40.0, location=(0.35, 0.2, 1.4), shape='SQUARE',
                size=0.3)
    return objs


def scene_disk_near(size=SIZE):
    # Issue 8: a large disk lamp (1.2 m) 3 cm above the receiver: only an exact
    # solid-angle sampler (or bsdf) gets the texels under it right.
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    U.add_light('AREA', "disk_near", energy=40.0, location=(0.2, -0.1, 0.03),
                shape='DISK', size=1.2)
    return objs


def scene_spread_walls(size=SIZE):
    # Issue 8: spread area lights close to surfaces: a narrow-spread rectangle
    # 30 cm from the receiver at a slant, a spread disk 40 cm above it, and a
    # wall beside them that also shadows.
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    U.add_light('AREA', "rect_spread30", energy=40.0, location=(-0.4, -0.3, 0.3),
                rotation=(U.deg(-20), U.deg(25), 0), shape='RECTANGLE', size=0.6,
                size_y=0.2, spread=U.deg(50))
    U.add_light('AREA', "disk_spread60", energy=30.0, location=(0.4, 0.3, 0.4),
                rotation=(0, U.deg(-15), 0), shape='DISK', size=0.4, spread=U.deg(90))
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0.0, 0.9, 0.25),
                                     rotation=(U.deg(90), 0, 0))
    wall = bpy.context.active_object
    wall.name = "wall"
    wall.scale = (2.0, 0.5, 1.0)
    return objs


def scene_world_window(size=SIZE):
    # Issue 9: a closed room lit by a constant world through a 0.5 m skylight
    # and by a small lamp inside: the effect plan leaves the world to its BSDF
    # rays (as Cycles), which must still find the sky through the opening.
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    h = 1.5
    for name, extent, center in (("wall_e", (0.1, 2.2, h), (1.05, 0, h / 2)),
                                 ("wall_w", (0.1, 2.2, h), (-1.05, 0, h / 2)),
                                 ("wall_n", (2.2, 0.1, h), (0, 1.05, h / 2)),
                                 ("wall_s", (2.2, 0.1, h), (0, -1.05, h / 2)),
                                 # the ceiling around the opening x ∈ [0.05, 0.55],
                                 # y ∈ [−0.05, 0.45]
                                 ("ceiling_w", (1.15, 2.2, 0.1), (-0.525, 0, h + 0.05)),
                                 ("ceiling_e", (0.55, 2.2, 0.1), (0.825, 0, h + 0.05)),
                                 ("ceiling_s", (0.5, 1.05, 0.1), (0.3, -0.575, h + 0.05)),
                                 ("ceiling_n", (0.5, 0.65, 0.1), (0.3, 0.775, h + 0.05))):
        U.add_box(name, extent, center)
    U.add_light('AREA', "lamp", energy=10.0, location=(-0.5, -0.4, 1.4), shape='SQUARE',
                size=0.3)
    U.constant_world(color=(0.5, 0.6, 0.8), strength=10.0)
    return objs


def _lightmapped_box(name, size, location, image_size, rotation=(0.0, 0.0, 0.0)):
    """A box (Blender's cube: its own UV layout) baking into an image of its own."""
    ob = U.add_box(name, size, location)
    ob.rotation_euler = rotation
    ob.data.materials.append(U.image_material(name + "Mat", U.make_image(name, image_size)))
    return ob


def scene_intersecting_boxes(size=SIZE):
    # Issue 32: two unit boxes of one height standing on z = 0, one turned
    # 30°, interpenetrating; each its own lightmap. Their tops are coplanar
    # where they overlap (Cycles: dark, the other box's top stops every ray),
    # and each has faces inside the other.
    objs = [_lightmapped_box("BoxA", (1.0, 1.0, 1.0), (0.0, 0.0, 0.5), size),
            _lightmapped_box("BoxB", (1.0, 1.0, 1.0), (0.55, 0.35, 0.5), size,
                             rotation=(0.0, 0.0, U.deg(30)))]
    U.add_light('POINT', "point", energy=600.0, location=(0.4, -1.6, 2.6),
                shadow_soft_size=0.2)
    U.add_light('AREA', "square", energy=200.0, location=(-1.4, 0.8, 1.8),
                rotation=(U.deg(-30), U.deg(-40), 0), shape='SQUARE', size=0.5)
    return objs


def scene_box_in_floor(size=SIZE):
    # Issue 32: a box sunk 0.2 m into the floor: the floor under it and the
    # box's sides below the floor are inside the other; both baked.
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2),
            _lightmapped_box("SunkBox", (0.6, 0.5, 0.6), (0.2, -0.1, 0.1), size // 2,
                             rotation=(0.0, 0.0, U.deg(20)))]
    U.add_light('AREA', "square", energy=80.0, location=(-0.3, -0.5, 1.2),
                rotation=(U.deg(20), U.deg(-15), 0), shape='SQUARE', size=0.6)
    U.add_light('SUN', "sun", energy=2.0, rotation=(U.deg(35), U.deg(15), 0), angle=U.deg(5))
    return objs


def scene_wall_through_wall(size=SIZE):
    # Issue 32: two 10 cm walls crossing like an X on a floor, each its own
    # lightmap: each wall's faces inside the other are dark.
    objs = [_lightmapped_box("WallA", (2.0, 0.1, 1.0), (0.0, 0.0, 0.5), size),
            _lightmapped_box("WallB", (2.0, 0.1, 1.0), (0.0, 0.0, 0.5), size,
                             rotation=(0.0, 0.0, U.deg(70)))]
    U.grid_mesh("Floor", size=3.0, cuts=1)
    U.add_light('AREA', "square", energy=150.0, location=(0.6, -0.9, 1.6),
                rotation=(U.deg(35), U.deg(15), 0), shape='SQUARE', size=0.5)
    U.add_light('POINT', "point", energy=200.0, location=(-0.8, 0.7, 1.4),
                shadow_soft_size=0.1)
    return objs


def scene_thin_wall_rooms(size=SIZE):
    # Issue 32: two rooms under one ceiling, parted by a 1 mm wall; a lamp
    # lights the left one. The right room's floor (the same mesh as the
    # left's) must stay black: no light through the thin wall or under it.
    img = U.make_image("bake", size)
    floor = receiver(img, size=2.0, cuts=2)
    h = 1.0
    for name, extent, center in (("wall_e", (0.1, 2.2, h), (1.05, 0, h / 2)),
                                 ("wall_w", (0.1, 2.2, h), (-1.05, 0, h / 2)),
                                 ("wall_n", (2.2, 0.1, h), (0, 1.05, h / 2)),
                                 ("wall_s", (2.2, 0.1, h), (0, -1.05, h / 2)),
                                 ("ceiling", (2.2, 2.2, 0.1), (0, 0, h + 0.05)),
                                 ("parting", (0.001, 2.0, h), (0.2, 0, h / 2))):
        U.add_box(name, extent, center)
    U.add_light('AREA', "lamp", energy=30.0, location=(-0.4, 0.0, 0.9), shape='SQUARE',
                size=0.3)
    U.add_light('POINT', "bulb", energy=20.0, location=(0.15, 0.3, 0.5), shadow_soft_size=0.02)
    return [floor]


def scene_blockout(size=SIZE):
    # Issue 32: a level block-out — a floor and twelve crates of four sizes
    # placed at random (fixed seed), several interpenetrating or sunk into the
    # floor, some of one height side by side; a lightmap per object, baked as
    # one selection, under a sun and two lamps.
    import random
    rng = random.Random(32)
    img = U.make_image("bake", size)
    objs = [receiver(img, name="Floor", size=4.0, cuts=3)]
    for i in range(12):
        side = rng.choice((0.4, 0.5, 0.6, 0.8))
        x, y = rng.uniform(-1.4, 1.4), rng.uniform(-1.4, 1.4)
        sink = rng.choice((0.0, 0.0, 0.1))
        objs.append(_lightmapped_box(f"Crate.{i:03d}", (side, side, side),
                                     (x, y, side / 2 - sink), max(8, size // 2),
                                     rotation=(0.0, 0.0, rng.uniform(0.0, 3.14159))))
    U.add_light('SUN', "sun", energy=2.0, rotation=(U.deg(40), U.deg(-20), U.deg(30)),
                angle=U.deg(4))
    U.add_light('AREA', "lamp", energy=300.0, location=(0.5, -0.8, 2.5),
                rotation=(U.deg(10), 0, 0), shape='SQUARE', size=0.8)
    U.add_light('POINT', "bulb", energy=150.0, location=(-1.0, 1.0, 1.5), shadow_soft_size=0.1)
    return objs


def _yard(size):
    """A floor with a wall and a pillar, open to the sky (the image-world scenes)."""
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    U.add_box("wall", (0.1, 1.2, 0.6), (0.6, 0.2, 0.3))
    U.add_box("pillar", (0.2, 0.2, 0.9), (-0.4, -0.3, 0.45))
    return objs


def scene_hdri_open(size=SIZE):
    # Issue 34: an Environment Texture sky with a small bright sun over occluders.
    objs = _yard(size)
    U.image_world(U.sky_image())
    return objs


def scene_hdri_rotated(size=SIZE):
    # The same sky turned by a Mapping node (Euler XYZ), with Strength 0.5.
    objs = _yard(size)
    U.image_world(U.sky_image(), strength=0.5, rotation=(U.deg(10), U.deg(-15), U.deg(70)))
    return objs


def scene_hdri_mix(size=SIZE):
    # The sky added to a constant Background (a mixed world).
    objs = _yard(size)
    U.image_world(U.sky_image(), mix_constant=((0.9, 0.7, 0.5), 0.6))
    return objs


def scene_sky_texture(size=SIZE):
    # A Nishita Sky Texture world (its sun disc included) over the yard.
    objs = _yard(size)
    world = U.constant_world()
    nodes = world.node_tree.nodes
    sky = nodes.new("ShaderNodeTexSky")
    sky.sky_type = 'NISHITA'
    sky.sun_elevation = U.deg(35)
    sky.sun_rotation = U.deg(60)
    sky.sun_size = U.deg(3)
    world.node_tree.links.new(sky.outputs["Color"], nodes["Background"].inputs["Color"])
    nodes["Background"].inputs["Strength"].default_value = 0.05
    return objs


def scene_hdri_window(size=SIZE):
    # A closed room lit only through a window in its east wall by the image sky,
    # whose sun shines through it onto the floor.
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    h = 1.5
    for name, extent, center in (("wall_w", (0.1, 2.2, h), (-1.05, 0, h / 2)),
                                 ("wall_n", (2.2, 0.1, h), (0, 1.05, h / 2)),
                                 ("wall_s", (2.2, 0.1, h), (0, -1.05, h / 2)),
                                 ("ceiling", (2.2, 2.2, 0.1), (0, 0, h + 0.05)),
                                 # the east wall around the window y ∈ [−0.4, 0.4],
                                 # z ∈ [0.5, 1.1]
                                 ("wall_e_low", (0.1, 2.2, 0.5), (1.05, 0, 0.25)),
                                 ("wall_e_high", (0.1, 2.2, 0.4), (1.05, 0, 1.3)),
                                 ("wall_e_s", (0.1, 0.7, 0.6), (1.05, -0.75, 0.8)),
                                 ("wall_e_n", (0.1, 0.7, 0.6), (1.05, 0.75, 0.8))):
        U.add_box(name, extent, center)
    U.image_world(U.sky_image(sun_elevation=35.0, sun_azimuth=0.0))
    return objs


SCENES = {
    "area": scene_area,
    "area_round": scene_area_round,
    "point_spot": scene_point_spot,
    "spot_radius": scene_spot_radius,
    "sun_occluder": scene_sun_occluder,
    "shared_image": scene_shared_image,
    "emission_world": scene_emission_world,
    "principled_r0": scene_principled_r0,
    "principled_r05": scene_principled_r05,
    "principled_r1": scene_principled_r1,
    "oren_nayar": scene_oren_nayar,
    "many_lights": scene_many_lights,
    "emissive_mesh": scene_emissive_mesh,
    "disk_near": scene_disk_near,
    "spread_walls": scene_spread_walls,
    "world_window": scene_world_window,
    "intersecting_boxes": scene_intersecting_boxes,
    "box_in_floor": scene_box_in_floor,
    "wall_through_wall": scene_wall_through_wall,
    "thin_wall_rooms": scene_thin_wall_rooms,
    "blockout": scene_blockout,
    "hdri_open": scene_hdri_open,
    "hdri_rotated": scene_hdri_rotated,
    "hdri_mix": scene_hdri_mix,
    "sky_texture": scene_sky_texture,
    "hdri_window": scene_hdri_window,
}

# Objects of a scene that have texels inside other objects (or on their
# faces), which a bake must report (BakeStats::buried_texels, issue 32); any
# scene not listed has none.
BURIED = {
    "intersecting_boxes": {"BoxA", "BoxB"},
    # The floor under the box; the box's faces below the floor lie under a
    # single plane, not inside anything (dark all the same).
    "box_in_floor": {"Receiver"},
    "wall_through_wall": {"WallA", "WallB"},
    "blockout": None,  # random placement: reported, not checked
    # The yard's wall and pillar stand on the floor: the floor under them.
    "hdri_open": {"Receiver"},
    "hdri_rotated": {"Receiver"},
    "hdri_mix": {"Receiver"},
    "sky_texture": {"Receiver"},
}


def images_of(objects):
    out = []
    for ob in objects:
        for slot in ob.material_slots:
            node = slot.material.node_tree.nodes.active
            if node.image not in out:
                out.append(node.image)
    return out
