"""Issue 12 items 4 and 5: words an artist knows, and the panel under every engine.

- Labels (what the panel shows) carry no research terms and fit the default editor
  width; the research names (SPEC §1–3) stay in the tooltips.
- Under Cycles the panel is a subpanel of Cycles' Bake panel; under EEVEE and
  Workbench a Render Properties panel of its own, which also shows Blender's bake
  output settings (Cycles' Output and Margin subpanels are not there). Each shows
  one Bake button, and a bake runs with EEVEE as the render engine.

    scripts/blender_run.sh tests/blender/test_artist_words.py
"""

import os
import re
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

import omis_bake  # noqa: E402
from omis_bake import settings  # noqa: E402

check = U.check

# Research terms that mean nothing (or something else) to an artist. "Direct" is
# Cycles' Lighting: Direct of the bake's Influence panel; "Mode" said nothing.
RESEARCH_TERMS = ("effect plan", "mis system", "parallel", "heuristic", "technique",
                  "optimal mis", "direct", "mode", "solid angle", "unoccluded", "bsdf")


def uses(term, text):
    return re.search(r"\b" + re.escape(term) + r"\b", text.lower()) is not None
# The Properties editor of Blender 3.4's default layout is ~300 px wide at UI scale 1;
# a one-column enum label has ~26 characters there before it is cut off.
MAX_LABEL = 26


def labels_of(props_rna, names):
    out = []
    for name in names:
        prop = props_rna.properties[name]
        out.append((name, prop.name))
        if prop.type == 'ENUM':
            out += [(f"{name}.{item.identifier}", item.name) for item in prop.enum_items]
    return out


def test_labels_and_tooltips():
    rna = bpy.context.scene.omis.bl_rna
    for where, label in labels_of(rna, settings.SETTING_NAMES):
        for term in RESEARCH_TERMS:
            check(not uses(term, label), f"{where}: label {label!r} uses the research term "
                                       f"{term!r}")
        check(len(label) <= MAX_LABEL, f"{where}: label {label!r} longer than {MAX_LABEL}")
    items = {item.identifier: item for item in rna.properties["techniques"].enum_items}
    for ident, spec_name, _, _ in settings.TECHNIQUES:
        check(f"'{spec_name}'" in items[ident].description,
              f"{ident}: the tooltip lacks the research name {spec_name}")
    # The add-on offers exactly the techniques the library knows (one owner of
    # the names: core/render/techniques.cpp, published as omis.TECHNIQUES).
    from omis_bake import native
    library = tuple(native.require().TECHNIQUES)
    offered = tuple(name for _, name, _, _ in settings.TECHNIQUES)
    check(offered == library, f"add-on techniques {offered} differ from omis' {library}")
    tooltip = rna.properties["use_optimal_mis"].description
    check("optimal multiple importance sampling" in tooltip, tooltip)
    check("effect plan" in rna.properties["technique_mode"].enum_items["AUTO"].description,
          "the Automatic tooltip should name the effect plan")


def draw(panel_name, engine):
    bpy.context.scene.render.engine = engine
    log = []
    panel = getattr(bpy.types, panel_name)
    fake = type("P", (), {"layout": U.FakeLayout(log)})()
    panel.draw(fake, bpy.context)
    return log


def test_panel_words():
    props = bpy.context.scene.omis
    props.technique_mode = 'MANUAL'
    props.last_status = "complete"
    props.last_plan = "effect plan: 1 light\n  bsdf ×1"
    try:
        log = draw("OMIS_PT_bake", 'CYCLES')
    finally:
        props.property_unset("technique_mode")
        props.property_unset("last_status")
        props.property_unset("last_plan")
    labels = [text.lower() for kind, text in log if kind == "label"]
    for term in ("effect plan", "mis system", "parallel"):
        check(not any(term in text for text in labels), f"the panel shows {term!r}: {labels}")
    for text in ("mean error", "95 % of texels", "half the error"):
        check(any(text in label for label in labels), f"the panel lacks {text!r}: {labels}")


def test_every_engine():
    panel = bpy.types.OMIS_PT_bake
    check(panel.bl_context == "render" and not getattr(panel, "bl_parent_id", ""),
          "the panel must be a Render Properties panel of its own")
    omis_panels = [name for name in dir(bpy.types) if name.startswith("OMIS_PT_")]
    check(omis_panels == ["OMIS_PT_bake"], f"one omis panel, not {omis_panels}")
    for engine in ('CYCLES', 'BLENDER_EEVEE', 'BLENDER_WORKBENCH'):
        bpy.context.scene.render.engine = engine
        check(panel.poll(bpy.context), f"{engine}: the panel is hidden")
        log = draw("OMIS_PT_bake", engine)
        for name in ("target", "margin", "margin_type", "use_clear", "use_selected_to_active",
                     "samples", "use_optimal_mis"):
            check(("prop", name) in log, f"{engine}: the panel does not show {name}")
    check([e for e in log if e[0] == "operator"] == [("operator", "omis.bake")],
          "one Bake button")

    # Selected to Active, refused: the panel says so before a bake, in words naming
    # the setting, with the setting at hand.
    bpy.context.scene.render.bake.use_selected_to_active = True
    log = draw("OMIS_PT_bake", 'CYCLES')
    labels = " ".join(text for kind, text in log if kind == "label")
    check("Selected to Active" in labels and ("prop", "use_selected_to_active") in log,
          f"no refusal shown for Selected to Active: {labels!r}")
    bpy.context.scene.render.bake.use_selected_to_active = False

    # A bake under EEVEE (omis needs nothing of Cycles).
    U.reset_scene(engine='BLENDER_EEVEE')
    img = U.make_image("eevee", 16)
    ob = U.image_grid("Plane", img, size=1.0)
    U.add_light('SUN', "sun", energy=2.0)
    U.select_only([ob])
    check(bpy.ops.omis.bake(samples=1) == {'FINISHED'}, "operator under EEVEE")
    px = U.pixels(img)
    # A sun of 2 W/m² straight down: E/π = 2/π on every baked texel.
    check(np.allclose(px[4:12, 4:12, 0], 2.0 / np.pi, rtol=1e-4), f"{px[8, 8]}")


def main():
    for test in (test_labels_and_tooltips, test_panel_words, test_every_engine):
        test()
        print(f"ok {test.__name__}")


main()
