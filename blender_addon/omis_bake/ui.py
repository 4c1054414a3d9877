"""The panel, under every render engine: under Cycles inside Render Properties ▸ Bake
(whose Output and Margin subpanels hold the target, clear and margin settings omis
reads), elsewhere (EEVEE, Workbench, …) a Render Properties panel of its own that
also shows those settings of scene.render.bake."""

import bpy

from . import native, operators
from .settings import settings_from

CYCLES_BAKE_PANEL = "CYCLES_RENDER_PT_bake"


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
    """Blender's own bake output settings (under Cycles its subpanels show them)."""
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
    _figure(box, "Error (mean)", f"{100 * props.last_mean_error:.2f} %")
    _figure(box, "Error (95 % of texels)", f"≤ {100 * props.last_error_p95:.2f} %")
    _figure(box, "Half the error", f"≤ {operators.format_seconds(props.last_halving_seconds)}"
                                   f" more")


def draw_omis(layout, context, with_output):
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
    if with_output:
        _draw_output(layout, context)
    if props.last_status:
        _draw_last(layout, props)


class OMIS_PT_bake(bpy.types.Panel):
    """Under Cycles: a subpanel of Render Properties ▸ Bake."""
    bl_label = "omis: Low-Noise Direct Light"
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "render"
    # bl_parent_id is set in prepare(): Cycles' Bake panel when it exists.
    COMPAT_ENGINES = {'CYCLES'}
    available = True   # False when Cycles is absent: then OMIS_PT_bake_engines shows

    @classmethod
    def poll(cls, context):
        return cls.available and context.engine in cls.COMPAT_ENGINES

    def draw_header(self, context):
        _draw_header(self, context)

    def draw(self, context):
        draw_omis(self.layout, context, with_output=False)


class OMIS_PT_bake_engines(bpy.types.Panel):
    """Under every other engine (EEVEE, Workbench, …): a Render Properties panel of its
    own, with Blender's bake output settings, since Cycles' Bake panel is not there."""
    bl_label = "Bake (omis: Low-Noise Direct Light)"
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "render"

    @classmethod
    def poll(cls, context):
        return not OMIS_PT_bake.poll(context)

    def draw_header(self, context):
        _draw_header(self, context)

    def draw(self, context):
        draw_omis(self.layout, context, with_output=True)


classes = (OMIS_PT_bake, OMIS_PT_bake_engines)


def prepare():
    """Hangs the Cycles panel under Cycles' Bake panel when Cycles is there."""
    if hasattr(bpy.types, CYCLES_BAKE_PANEL):
        OMIS_PT_bake.bl_parent_id = CYCLES_BAKE_PANEL
        OMIS_PT_bake.available = True
    else:
        OMIS_PT_bake.available = False
        if "bl_parent_id" in OMIS_PT_bake.__dict__:
            del OMIS_PT_bake.bl_parent_id
