"""The exporter's receiver closures (issue 12): which material gives which
closure, and the warnings for what omis does not model.

    scripts/blender_run.sh tests/blender/test_receiver_export.py
"""

import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

from omis_bake import export, native  # noqa: E402

native.load()


def surface(name, kind=None, **inputs):
    """An image material whose surface is a new node of `kind` (None: the
    default Principled BSDF), with the given unlinked input values."""
    mat = U.image_material(name, U.make_image(name + "Img", 8))
    tree = mat.node_tree
    node = tree.nodes["Principled BSDF"]
    if kind is not None:
        tree.nodes.remove(node)
        node = tree.nodes.new(kind)
        tree.links.new(node.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    for key, value in inputs.items():
        node.inputs[key].default_value = value
    return mat, node


def receiver_of(material):
    problems = []
    return export.material_receiver(material, problems), problems


def main():
    U.reset_scene()
    check = U.check
    mat, _ = surface("Default")
    check(receiver_of(mat) == (("principled", 0.5), []), f"default: {receiver_of(mat)}")
    mat, _ = surface("Smooth", Roughness=0.0)
    check(receiver_of(mat)[0] == ("principled", 0.0), "Principled at roughness 0")
    mat, _ = surface("Lambert", "ShaderNodeBsdfDiffuse", Roughness=0.0)
    check(receiver_of(mat) == (None, []), "Diffuse BSDF at roughness 0 is Lambert")
    mat, _ = surface("Rough", "ShaderNodeBsdfDiffuse", Roughness=0.7)
    r, problems = receiver_of(mat)
    check(r[0] == "oren-nayar" and abs(r[1] - 0.7) < 1e-6 and not problems, f"{r} {problems}")
    check(receiver_of(None) == (None, []), "no material: Cycles' default diffuse")

    mat, _ = surface("Glossy", "ShaderNodeBsdfGlossy")
    r, problems = receiver_of(mat)
    check(r is None and any("neither a Principled nor a Diffuse" in p for p in problems),
          f"glossy: {problems}")
    mat, _ = surface("Sheen", Sheen=0.5)
    r, problems = receiver_of(mat)
    check(r == ("principled", 0.5) and any("Sheen" in p for p in problems), f"{problems}")
    mat, node = surface("Textured")
    noise = mat.node_tree.nodes.new("ShaderNodeTexNoise")
    mat.node_tree.links.new(noise.outputs["Fac"], node.inputs["Roughness"])
    r, problems = receiver_of(mat)
    check(r == ("principled", 0.5) and any("linked" in p for p in problems), f"{problems}")

    # Through a whole export: two materials on one object become two meshes with
    # their own receivers; the warnings reach the export.
    ob = U.grid_mesh("Two", size=2.0, cuts=1)
    rough, _ = surface("RoughTwo", "ShaderNodeBsdfDiffuse", Roughness=0.4)
    glossy, _ = surface("GlossyTwo", "ShaderNodeBsdfGlossy")
    ob.data.materials.append(rough)
    ob.data.materials.append(glossy)
    ob.data.polygons[0].material_index = 1
    U.add_light('SUN', "sun", energy=1.0)
    bpy.context.view_layer.update()
    e = export.export_scene(bpy.context, [ob], 'IMAGE_TEXTURES', omis=native.omis,
                            units=native.units)
    check(e.counts["receivers"] == {"oren-nayar": 1}, f"receivers {e.counts['receivers']}")
    check(e.counts["meshes"] == 2, f"meshes {e.counts['meshes']}")
    check(any("GlossyTwo" in w for w in e.warnings), f"warnings {e.warnings}")
    print("receiver export: ok")


main()
