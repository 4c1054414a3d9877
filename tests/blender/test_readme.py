"""README.md's Python snippets run as written: the Blender one on the demo room's
floor (selected, as an artist would), the module one in a temporary folder.
Each snippet is the ```python block after its `<!-- readme-snippet:NAME -->` line."""

import os
import re
import sys
import tempfile

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import omis_test_utils as U  # noqa: E402


def snippet(name):
    with open(os.path.join(ROOT, "README.md"), encoding="utf-8") as f:
        text = f.read()
    found = re.search(rf"<!-- readme-snippet:{name} -->\s*```python\n(.*?)```", text, re.S)
    U.check(found is not None, f"README.md: no python block after readme-snippet:{name}")
    return found.group(1)


def main():
    floor = U.demo_room(64)[0]
    U.select_only([floor])
    image = floor.active_material.node_tree.nodes.active.image
    before = U.pixels(image).copy()
    scope = {}
    exec(compile(snippet("blender"), "README.md:blender", "exec"), scope)
    U.check(scope["stats"]["samples_per_texel"] >= 1, "the Blender snippet baked nothing")
    U.check((U.pixels(image) != before).any(), "the Blender snippet left the image as it was")

    os.chdir(tempfile.mkdtemp(prefix="omis_readme_"))
    scope = {}
    exec(compile(snippet("module"), "README.md:module", "exec"), scope)
    U.check(os.path.getsize("floor.png") > 0, "the module snippet wrote no floor.png")
    U.check(scope["result"].stats["samples_per_texel"] >= 1, "the module snippet baked nothing")
    print("ok test_readme")


main()
