"""Run by test_package.sh: installs the zip as Preferences ▸ Add-ons ▸ Install does,
enables it and bakes with the bundled native module."""
import os
import sys

import addon_utils
import bpy

zip_path = os.environ["OMIS_TEST_ZIP"]
user = os.environ["BLENDER_USER_SCRIPTS"]
assert "omis" not in sys.modules
result = bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
assert result == {'FINISHED'}, result
installed = os.path.join(user, "addons", "omis_bake")
assert os.path.isfile(os.path.join(installed, "omis", "libomis.so.0")), os.listdir(installed)
addon_utils.modules_refresh()
module = addon_utils.enable("omis_bake", default_set=True, handle_error=lambda e: print(e))
assert module is not None, "enable failed"
import omis_bake  # noqa: E402
from omis_bake import native  # noqa: E402

assert native.load(), native.error
assert native.origin == "bundled", native.origin
assert native.location.startswith(user), native.location
assert "omis" not in sys.modules, "the top-level omis must not be imported"
print("bundled omis", native.omis.__version__, "from", native.location)

for ob in list(bpy.data.objects):
    bpy.data.objects.remove(ob)
bpy.ops.mesh.primitive_plane_add(size=1.0)
plane = bpy.context.active_object
image = bpy.data.images.new("pkg", 8, 8, float_buffer=True)
mat = bpy.data.materials.new("pkg")
mat.use_nodes = True
node = mat.node_tree.nodes.new("ShaderNodeTexImage")
node.image = image
mat.node_tree.nodes.active = node
plane.data.materials.append(mat)
light = bpy.data.objects.new("sun", bpy.data.lights.new("sun", 'SUN'))
bpy.context.scene.collection.objects.link(light)
light.data.energy = 3.14159265
light.data.angle = 0.0
bpy.context.scene.world = None
stats = omis_bake.bake(bpy.context, [plane], samples=4, margin=0)
value = image.pixels[0]
assert abs(value - 1.0) < 1e-3, value
print("package test: baked", stats["covered"], "texels, value", value)
addon_utils.disable("omis_bake", default_set=True)
