"""The panel: Render Properties ▸ Bake (omis), after the engine's own panels, one panel
under every render engine with its one Bake button, omis' sampling settings, the
settings of scene.render.bake omis reads (target, clear, margin, selected to active —
under Cycles its own Bake panel shows the same settings) and the last bake's summary
with its warnings. Everything fits the default Properties width: short labels, the
long text in tooltips, long messages wrapped to the region's width."""

import bpy

from . import native, operators
from .settings import settings_from

# Blender's layout in pixels at UI scale 1 (the fit of the panel's text at the default
# Properties width rests on these; tests/blender/test_panel_screenshot.py checks it):
# the panel's inner margins left and right, a box's padding on each side, an icon,
# the space a label keeps around its text, and the share of the width the label of
# a property takes in a split layout (Blender's UI_ITEM_PROP_SEP_DIVIDE).
PANEL_MARGIN = 16
BOX_PADDING = 8
ICON_WIDTH = 20
TEXT_MARGIN = 8
PROPERTY_SPLIT = 0.4
# The default Properties editor of Blender 3.4's layout on a 1920-pixel screen: its
# panels' region is about 303 pixels wide. Wrapping without a region uses it.
DEFAULT_REGION_WIDTH = 303
# How many warnings the Last bake box shows before "more".
FIRST_WARNINGS = 2


def ui_scale():
    """Blender's interface scale (with the display's DPI); 1 without a window."""
    try:
        scale = float(bpy.context.preferences.system.ui_scale)
    except AttributeError:
        scale = 0.0
    return scale if scale > 0 else 1.0


def text_width(text):
    """Width in pixels of `text` in Blender's UI font at the current scale."""
    try:
        import blf
        points = bpy.context.preferences.ui_styles[0].widget.points
        blf.size(0, points * ui_scale())
        return blf.dimensions(0, text)[0]
    except (ImportError, AttributeError, IndexError):
        return 6.5 * ui_scale() * len(text)   # no font (e.g. a script without UI)


def panel_width(context):
    """The width a panel's layout has in the current region, in pixels."""
    region = getattr(context, "region", None)
    width = region.width if region is not None and region.width > 1 else DEFAULT_REGION_WIDTH
    return width - 2 * PANEL_MARGIN * ui_scale()


def in_box(width):
    return width - 2 * BOX_PADDING * ui_scale()


def wrap_lines(text, width, icon=True):
    """`text` cut into lines at word boundaries that fit `width` pixels in a label
    (with an icon or the blank beside it on every line)."""
    room = width - (ICON_WIDTH * icon + TEXT_MARGIN) * ui_scale()
    lines, line = [], ""
    for word in _pieces(text.split(), room):
        candidate = f"{line} {word}" if line else word
        if line and text_width(candidate) > room:
            lines.append(line)
            line = word
        else:
            line = candidate
    if line:
        lines.append(line)
    return lines


def _pieces(words, room):
    """The words, each one wider than `room` (a Python path) cut where the next
    character would not fit, after a '.' or '_' when there is one."""
    for word in words:
        while text_width(word) > room and len(word) > 1:
            cut = 1
            while cut < len(word) and text_width(word[:cut + 1]) <= room:
                cut += 1
            soft = max(word.rfind(".", 0, cut), word.rfind("_", 0, cut))
            cut = soft + 1 if soft > 0 else cut
            yield word[:cut]
            word = word[cut:]
        yield word


def _wrapped(layout, text, width, icon='NONE'):
    """A long text as labels that fit `width` pixels (the first line with `icon`)."""
    col = layout.column(align=True)
    for i, line in enumerate(wrap_lines(text, width, icon != 'NONE')):
        col.label(text=line, icon=icon if i == 0 else ('BLANK1' if icon != 'NONE' else 'NONE'))


def _figure(layout, name, value):
    split = layout.split(factor=0.48)
    left = split.row()
    left.alignment = 'RIGHT'
    left.label(text=name)
    split.label(text=value)


def _draw_header_progress(panel, context):
    """While baking, the panel's header shows the progress and the time left at its
    right end (the panel's name keeps its room)."""
    job = operators.running
    if job is not None:
        panel.layout.label(text=operators.header_text(job))


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
    _wrapped(box, reason, in_box(panel_width(context)), icon='ERROR')
    bake = context.scene.render.bake
    if bake.use_selected_to_active:
        box.prop(bake, "use_selected_to_active")


def _draw_running(layout, context, job):
    box = layout.box()
    width = in_box(panel_width(context))
    _wrapped(box, f"Baking: {operators.progress_text(job)}", width, icon='TIME')
    _wrapped(box, "Esc cancels; nothing is written until the bake ends", width, icon='BLANK1')


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
    row = layout.row(heading="Noise Limit")
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


def warnings_of(props):
    """The last bake's warnings, as the bake returned them (one per line)."""
    return [w for w in props.last_warnings.split("\n") if w]


def _draw_warnings(box, props, width):
    """How many, the first ones, the rest on demand (a disclosure toggle)."""
    warnings = warnings_of(props)
    if not warnings:
        return
    col = box.column()
    col.use_property_split = False   # the toggle: its triangle, then its text
    show = warnings if props.show_all_warnings else warnings[:FIRST_WARNINGS]
    for warning in show:
        _wrapped(col, warning, width, icon='DOT')
    hidden = len(warnings) - FIRST_WARNINGS
    if hidden > 0:
        text = "Show fewer" if props.show_all_warnings else \
            f"{hidden} more warning{'s' if hidden > 1 else ''}"
        row = col.row()
        row.alignment = 'LEFT'
        row.prop(props, "show_all_warnings", text=text, emboss=False,
                 icon='DISCLOSURE_TRI_DOWN' if props.show_all_warnings
                 else 'DISCLOSURE_TRI_RIGHT')


def _draw_last(layout, context, props):
    box = layout.box()
    width = in_box(panel_width(context))
    warnings = warnings_of(props)
    status = operators.status_text(props.last_status, warnings)
    _wrapped(box, f"Last bake: {status}", width, icon='ERROR' if warnings else 'INFO')
    _draw_warnings(box, props, width)
    unit = operators.per_unit(props.last_target)
    _figure(box, "Time", operators.format_seconds(props.last_seconds))
    samples = props.last_samples_per_texel
    _figure(box, "Samples", f"{samples:.1f} per {unit}" if samples < 100 else
            f"{samples:.0f} per {unit}")
    # Without a noise limit the error is an upper estimate (one sequence per texel:
    # computed as for independent samples).
    bound = "" if props.last_error_measured else "≤ "
    _figure(box, "Mean error", f"{bound}{100 * props.last_mean_error:.2f} %")
    _figure(box, "95 % of " + ("vertices" if unit == "vertex" else "texels"),
            f"≤ {100 * props.last_error_p95:.2f} %")
    more = operators.format_seconds(props.last_halving_seconds)
    if props.last_halving_measured:
        _figure(box, "Half the error", f"~{more} more")
    else:
        # One pass (a sample budget alone) shows no convergence: the 1/√n bound.
        _figure(box, "Half the error", f"≤ {more} more")
        _wrapped(box, "A Time Limit measures the time to halve the error", width,
                 icon='BLANK1')


def draw_omis(layout, context):
    layout.use_property_split = True
    layout.use_property_decorate = False
    props = context.scene.omis

    if not native.load():
        box = layout.box()
        box.alert = True
        _wrapped(box, "The omis native module is not available: " + native.error,
                 in_box(panel_width(context)), icon='ERROR')
    _draw_refusal(layout, context)
    job = operators.running
    if job is not None:
        _draw_running(layout, context, job)

    row = layout.row()
    row.scale_y = 1.4
    row.enabled = native.omis is not None and job is None
    row.operator("omis.bake", text="Bake", icon='RENDER_STILL')

    _draw_sampling(layout, props)
    _draw_output(layout, context)
    if props.last_status:
        _draw_last(layout, context, props)


class OMIS_PT_bake(bpy.types.Panel):
    """Render Properties ▸ omis Bake, under every render engine: a panel of its own with
    its one Bake button. Cycles' Bake panel keeps Cycles' own button (it bakes with
    Cycles); nesting omis inside it put two Bake buttons in one panel."""
    # Short: while baking, the header also shows the progress.
    bl_label = "Bake (omis)"
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "render"
    # Below the engine's own panels (Cycles' Bake among them), like Blender's own
    # later additions; a panel without bl_parent_id is top-level.
    bl_order = 100

    @classmethod
    def poll(cls, context):
        return True   # omis needs nothing from the render engine

    def draw_header_preset(self, context):
        _draw_header_progress(self, context)

    def draw(self, context):
        draw_omis(self.layout, context)


classes = (OMIS_PT_bake,)
