"""The panel: Render Properties ▸ Bake ▸ omis (Cycles)."""

import bpy

from . import native, operators

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


class OMIS_PT_bake(bpy.types.Panel):
    bl_label = "omis: Optimal MIS"
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "render"
    # bl_parent_id is set in register(): Cycles' Bake panel when it exists.
    COMPAT_ENGINES = {'CYCLES'}
    standalone = False   # True when Cycles is absent: then shown for every engine

    @classmethod
    def poll(cls, context):
        return cls.standalone or context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        props = context.scene.omis

        if not native.load():
            box = layout.box()
            box.alert = True
            _wrapped(box, "The omis native module is not available: " + native.error,
                     icon='ERROR')

        job = operators.running
        if job is not None:
            box = layout.box()
            state = "cancelling…" if job.cancel_requested else f"{100 * job.fraction:.0f} %"
            box.label(text=f"Baking: {state}", icon='TIME')
            if job.current_label:
                box.label(text=job.current_label, icon='BLANK1')
            box.label(text="Esc cancels; nothing is written until the bake ends", icon='BLANK1')

        row = layout.row()
        row.scale_y = 1.4
        row.enabled = native.omis is not None and job is None
        row.operator("omis.bake", text="Bake", icon='RENDER_STILL')

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

        row = layout.row()
        row.prop(props, "technique_mode", expand=True)
        if props.technique_mode == 'MANUAL':
            flow = layout.grid_flow(row_major=True, columns=2, even_columns=True, align=True)
            flow.use_property_split = False
            flow.prop(props, "techniques", expand=True)

        col = layout.column(align=True)
        col.prop(props, "samples")
        col.prop(props, "time_budget")
        row = layout.row(heading="Noise Target")
        row.prop(props, "use_noise_target", text="")
        sub = row.row()
        sub.active = props.use_noise_target
        sub.prop(props, "noise_target", text="")

        col = layout.column()
        col.prop(props, "target")
        if props.target == 'IMAGE_TEXTURES':
            col.prop(props, "use_clear")
            col.prop(props, "margin")
        col.prop(props, "seed")

        if props.last_status:
            box = layout.box()
            box.label(text="Last bake", icon='INFO')
            for name, value in (
                    ("Time", f"{props.last_seconds:.2f} s ({props.last_status})"),
                    ("Samples per texel", f"{props.last_samples_per_texel:.1f}"),
                    ("Mean relative error", f"{100 * props.last_mean_error:.2f} %")):
                split = box.split(factor=0.45)
                left = split.row()
                left.alignment = 'RIGHT'
                left.label(text=name)
                split.label(text=value)
            if props.last_plan:
                plan = box.column(align=True)
                for line in props.last_plan.splitlines():
                    if line.strip():
                        plan.label(text=line.replace("  ", "   "))


classes = (OMIS_PT_bake,)


def prepare():
    """Hangs the panel under Cycles' Bake panel when Cycles is there."""
    if hasattr(bpy.types, CYCLES_BAKE_PANEL):
        OMIS_PT_bake.bl_parent_id = CYCLES_BAKE_PANEL
        OMIS_PT_bake.bl_label = "omis: Optimal MIS"
        OMIS_PT_bake.standalone = False
    else:
        OMIS_PT_bake.standalone = True
        if "bl_parent_id" in OMIS_PT_bake.__dict__:
            del OMIS_PT_bake.bl_parent_id
        OMIS_PT_bake.bl_label = "omis Bake: Optimal MIS"
