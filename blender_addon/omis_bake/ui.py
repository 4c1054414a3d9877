"""The panel: Render Properties ▸ Bake (omis), one panel under every render engine
with its one Bake button, omis' sampling settings and the settings of
scene.render.bake omis reads (target, clear, margin, selected to active — under
Cycles its own Bake panel shows the same settings)."""

import bpy

from . import native, operators
from .settings import settings_from

def _wrapped(layout, text, width=60, icon='NONE'):
    words, line, first = text.split(), "", True
    for word in words:
        if line and len(line) + 1 + len(word) > width:
            layout.label(text=line, icon=icon if first else 'BLANK1')
            line, first = word, False
        else:
            line = f"{line} {word}" if line else word
    if line:
        layout.label(text=line, icon=icon if first else 'BLANK1')


def _figure(layout, name, value):
    split = layout.split(factor=0.45)
    left = split.row()
    left.alignment = 'RIGHT'
    left.label(text=name)
    split.label(text=value)


def _draw_header(panel, context):
    """While baking, the panel's header shows the progress and the time left."""
    job = operators.running
    if job is not None:
        panel.layout.label(text=operators.progress_text(job).split(" (")[0], icon='TIME')


def _draw_refusal(layout, context):
    """Blender bake settings omis cannot honour: say so before the bake, with the
    setting itself to change right there."""
    try:
        reason = settings_from(context.scene.omis).unsupported()
    except (ValueError, TypeError) as exc:
        reason = str(exc)
    if reason is None:
        return
    box = layout.box()
    box.alert = True
    _wrapped(box, reason, icon='ERROR')
    bake = context.scene.render.bake
    if bake.use_selected_to_active:
        box.prop(bake, "use_selected_to_active")


def _draw_running(layout, job):
    box = layout.box()
    box.label(text=f"Baking: {operators.progress_text(job)}", icon='TIME')
    box.label(text="Esc cancels; nothing is written until the bake ends", icon='BLANK1')


def _draw_sampling(layout, props):
    col = layout.column()
    col.prop(props, "use_optimal_mis")
    sub = col.column()
    if props.use_optimal_mis:
        sub.prop(props, "optimal_mode")
    else:
        sub.prop(props, "heuristic")
        if props.heuristic == 'POWER':
            sub.prop(props, "power_beta")
        elif props.heuristic == 'CUTOFF':
            sub.prop(props, "cutoff_threshold")

    layout.prop(props, "technique_mode")
    if props.technique_mode == 'MANUAL':
        # One column: the labels fit the default editor width.
        col = layout.column(align=True)
        col.use_property_split = False
        col.prop(props, "techniques", expand=True)

    col = layout.column(align=True)
    col.prop(props, "samples")
    col.prop(props, "time_budget")
    row = layout.row(heading="Noise Threshold")
    row.prop(props, "use_noise_target", text="")
    sub = row.row()
    sub.active = props.use_noise_target
    sub.prop(props, "noise_target", text="")
    layout.prop(props, "seed")


def _draw_output(layout, context):
    """Blender's own bake output settings, which omis reads (under Cycles its Bake
    panel's subpanels show the same settings)."""
    bake = context.scene.render.bake
    col = layout.column()
    col.prop(bake, "target")
    if bake.target == 'IMAGE_TEXTURES':
        col.prop(bake, "use_clear", text="Clear Image")
        # As Cycles' Margin subpanel: short labels under a heading (they fit the
        # default editor width).
        col.label(text="Margin")
        col.prop(bake, "margin_type", text="Type")
        col.prop(bake, "margin", text="Size")
    col.prop(bake, "use_selected_to_active")


def _draw_last(layout, props):
    box = layout.box()
    box.label(text="Last bake", icon='INFO')
    _figure(box, "Time", f"{operators.format_seconds(props.last_seconds)} "
                         f"({props.last_status})")
    _figure(box, "Samples per texel", f"{props.last_samples_per_texel:.1f}")
    # Without a noise threshold the error is an upper estimate (one sequence
    # per texel: computed as for independent samples).
    bound = "" if props.last_error_measured else "≤ "
    _figure(box, "Error (mean)", f"{bound}{100 * props.last_mean_error:.2f} %")
    _figure(box, "Error (95 % of texels)", f"≤ {100 * props.last_error_p95:.2f} %")
    more = operators.format_seconds(props.last_halving_seconds)
    if props.last_halving_measured:
        _figure(box, "Half the error", f"{more} more (estimated)")
    else:
        # One pass (a sample budget alone) shows no convergence: the 1/√n bound.
        _figure(box, "Half the error", f"≤ {more} more")
        _figure(box, "", "(a Time Limit measures it)")


def draw_omis(layout, context):
    layout.use_property_split = True
    layout.use_property_decorate = False
    props = context.scene.omis

    if not native.load():
        box = layout.box()
        box.alert = True
        _wrapped(box, "The omis native module is not available: " + native.error,
                 icon='ERROR')
    _draw_refusal(layout, context)
    job = operators.running
    if job is not None:
        _draw_running(layout, job)

    row = layout.row()
    row.scale_y = 1.4
    row.enabled = native.omis is not None and job is None
    row.operator("omis.bake", text="Bake", icon='RENDER_STILL')

    _draw_sampling(layout, props)
    _draw_output(layout, context)
    if props.last_status:
        _draw_last(layout, props)


class OMIS_PT_bake(bpy.types.Panel):
    """Render Properties ▸ omis Bake, under every render engine: a panel of its own with
    its one Bake button. Cycles' Bake panel keeps Cycles' own button (it bakes with
    Cycles); nesting omis inside it put two Bake buttons in one panel."""
    bl_label = "Bake (omis: Low-Noise Direct Light)"
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "render"
    # Below the engine's own panels (Cycles' Bake among them), like Blender's own
    # later additions; a panel without bl_parent_id is top-level.
    bl_order = 100

    @classmethod
    def poll(cls, context):
        return True   # omis needs nothing from the render engine

    def draw_header(self, context):
        _draw_header(self, context)

    def draw(self, context):
        draw_omis(self.layout, context)


classes = (OMIS_PT_bake,)
