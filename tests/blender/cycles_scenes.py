"""The scenes of the Cycles-agreement test (every light type, occluders, two
objects sharing an image, emission and a world), shared with the equal-time
benchmark (bench/bench_cycles.py). Each builder adds its objects to the current
(reset) scene and returns the objects to bake; all of them bake into one image
of `size`² texels.
"""

import bpy

import omis_test_utils as U

SIZE = 64


def receiver(image, name="Receiver", **kwargs):
    ob = U.grid_mesh(name, **kwargs)
    ob.data.materials.append(U.image_material(name + "Mat", image))
    return ob


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


def scene_point_spot(size=SIZE):
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    U.add_light('POINT', "point_radius", energy=150.0, location=(-0.5, -0.5, 1.0),
                shadow_soft_size=0.2)
    U.add_light('SPOT', "spot", energy=400.0, location=(0.4, 0.3, 1.2),
                rotation=(U.deg(15), U.deg(-10), 0), spot_size=U.deg(60), spot_blend=0.3,
                shadow_soft_size=0.0)
    return objs


def scene_spot_radius(size=SIZE):
    # Cycles 3.4 applies the spot cone to each sampled point of the light's disk
    # (direction -ls->D); omis uses the cone at the light's centre. Fails until
    # the core follows Cycles (the ctest entry is disabled meanwhile).
    img = U.make_image("bake", size)
    objs = [receiver(img, size=2.0, cuts=2)]
    U.add_light('SPOT', "spot_radius", energy=400.0, location=(0.4, 0.3, 1.2),
                rotation=(U.deg(15), U.deg(-10), 0), spot_size=U.deg(60), spot_blend=0.3,
                shadow_soft_size=0.1)
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
    mat = bpy.data.materials.new("Glow")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    em = nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (1.0, 0.8, 0.6, 1.0)
    em.inputs["Strength"].default_value = 6.0
    mat.node_tree.links.new(em.outputs[0], nodes["Material Output"].inputs["Surface"])
    emitter.data.materials.append(mat)
    U.add_box("occluder", (0.4, 0.4, 0.05), (-0.4, 0.0, 0.35))
    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0.3, 0.4, 0.5, 1.0)
    bg.inputs["Strength"].default_value = 0.5
    bpy.context.scene.world = world
    return objs


SCENES = {
    "area": scene_area,
    "area_round": scene_area_round,
    "point_spot": scene_point_spot,
    "spot_radius": scene_spot_radius,
    "sun_occluder": scene_sun_occluder,
    "shared_image": scene_shared_image,
    "emission_world": scene_emission_world,
}


def images_of(objects):
    out = []
    for ob in objects:
        for slot in ob.material_slots:
            node = slot.material.node_tree.nodes.active
            if node.image not in out:
                out.append(node.image)
    return out
