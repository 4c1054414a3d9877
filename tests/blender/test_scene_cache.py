"""The committed scene kept between bakes (omis_bake/scene_cache.py): an unchanged
scene is reused and bakes the same bits; after any change that reaches omis — a
light's strength or place, a mesh's vertices, a modifier, an object hidden, an
emissive material, the receiver's material, the world — the next bake commits
anew and gives exactly what a bake without the kept scene gives.

The same for the meshes kept between exports (omis_bake/mesh_cache.py): an
unchanged occluder or emitter is not read again, and after a change that keeps
its vertices (material indices) or one no depsgraph update reports (a shape
key animated over a frame change) the bake equals one without kept reads.

    scripts/blender_run.sh tests/blender/test_scene_cache.py
"""

import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

from omis_bake import mesh_cache, scene_cache  # noqa: E402
from omis_bake.job import BakeJob  # noqa: E402
from omis_bake.settings import settings_from  # noqa: E402

check = U.check


def build():
    U.reset_scene()
    img = U.make_image("bake", 16)
    receiver = U.image_grid("Receiver", img, material="ReceiverMat", size=2.0, cuts=2)
    U.add_light('AREA', "lamp", energy=200.0, location=(0.2, 0.1, 1.2), size=0.6)
    U.add_box("occluder", (0.4, 0.4, 0.05), (0.0, 0.0, 0.5))
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1, radius=0.1, location=(-0.5, 0.4, 0.4))
    glow = bpy.context.active_object
    glow.name = "glow"
    glow.data.materials.append(U.emission_material("Glow", strength=4.0))
    glow.data.materials.append(U.emission_material("Dim", strength=0.5))  # slot 1: unused
    # A second occluder rises from frame 1 to 2 by a shape key.
    mover = U.add_box("mover", (0.2, 0.2, 0.05), (0.5, -0.4, 0.3))
    mover.shape_key_add(name="Basis")
    raised = mover.shape_key_add(name="raised")
    for point in raised.data:
        point.co.z += 0.2
    for frame, value in ((1, 0.0), (2, 1.0)):
        raised.value = value
        raised.keyframe_insert("value", frame=frame)
    bpy.context.scene.frame_set(1)
    U.constant_world(strength=0.2)
    return receiver, img


def bake(receiver, img):
    """(pixels, reused): a fixed-seed 8-sample bake through the add-on's job."""
    U.set_pixels(img, (0.0, 0.0, 0.0, 0.0))
    U.select_only([receiver])
    settings = settings_from(bpy.context.scene.omis,
                             {"samples": 8, "time_budget": 0.0, "use_noise_target": False,
                              "seed": 5, "margin": 0, "use_clear": True})
    job = BakeJob(bpy.context, [receiver], settings)
    job.run()
    job.finish(bpy.context)
    return U.pixels(img).copy(), job.scene_reused


def fresh(receiver, img):
    """The same bake with no kept scene and no kept mesh reads."""
    scene_cache.clear()
    mesh_cache.clear()
    pixels, reused = bake(receiver, img)
    check(not reused, "a bake after clear() reused a scene")
    return pixels


def move_vertex():
    me = bpy.data.objects["occluder"].data
    for v in me.vertices[:4]:
        v.co.x += 1.0
    me.update()


def glow_material_index():
    me = bpy.data.objects["glow"].data
    for polygon in list(me.polygons)[::2]:
        polygon.material_index = 1  # same vertices, half the faces dimmer


def add_modifier():
    md = bpy.data.objects["occluder"].modifiers.new("Array", 'ARRAY')  # a second box beside
    md.count = 2
    md.relative_offset_displace = (0.0, -1.5, 0.0)


CHANGES = {
    "light strength": lambda: setattr(bpy.data.lights["lamp"], "energy", 320.0),
    "light moved": lambda: setattr(bpy.data.objects["lamp"], "location", (0.4, -0.2, 1.0)),
    "mesh vertex": move_vertex,
    "modifier": add_modifier,
    "material index": glow_material_index,
    "frame with a shape key": lambda: bpy.context.scene.frame_set(2),
    "occluder hidden": lambda: bpy.data.objects["occluder"].hide_set(True),
    "emission strength": lambda: setattr(
        bpy.data.materials["Glow"].node_tree.nodes["Emission"].inputs["Strength"],
        "default_value", 9.0),
    "receiver material": lambda: setattr(
        bpy.data.materials["ReceiverMat"].node_tree.nodes["Principled BSDF"].inputs["Roughness"],
        "default_value", 0.9),
    "world strength": lambda: setattr(
        bpy.context.scene.world.node_tree.nodes["Background"].inputs["Strength"],
        "default_value", 0.6),
}


def main():
    receiver, img = build()
    scene_cache.clear()
    before, reused = bake(receiver, img)
    check(not reused, "the first bake reused a scene")
    hits = mesh_cache.stats["hits"]
    again, reused = bake(receiver, img)
    check(reused, "an unchanged scene was committed again")
    check(np.array_equal(again, before), "the reused scene baked other values")
    check(mesh_cache.stats["hits"] >= hits + 2, "the occluder and emitter were read again")

    for name, change in CHANGES.items():
        change()
        bpy.context.view_layer.update()
        after, reused = bake(receiver, img)
        check(not reused, f"{name}: the changed scene reused the last one")
        check(not np.array_equal(after, before), f"{name}: the change did not change the bake")
        expected = fresh(receiver, img)
        check(np.array_equal(after, expected),
              f"{name}: differs from a bake without the kept scene")
        again, reused = bake(receiver, img)
        check(reused and np.array_equal(again, after), f"{name}: not reused when unchanged")
        before = after
        U.log(f"  {name}: committed anew, same bits as a fresh bake")
    U.log("test_scene_cache: ok")


main()
