"""The bake settings: one table feeding the scene's PropertyGroup (`scene.omis`),
the operator's arguments (`bpy.ops.omis.bake(...)`) and the scripting call
(`omis_bake.bake(context, **settings)`), so the three never drift apart."""

from dataclasses import dataclass, fields

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

# Technique identifiers (Blender style), their SPEC §3 names, the panel's label in an
# artist's words (short enough for the default editor width) and the tooltip, which
# keeps the research name. Built from the same parts as the library's own list
# (`omis.TECHNIQUES`, core/render/techniques.cpp): `bsdf`, then every light
# selection with every shape sampler; the Blender tests check the two agree.
_SELECTIONS = (  # SPEC name, label, tooltip start
    ("uniform", "Any Light", "Each light equally often"),
    ("power", "Bright Lights", "Brighter lights more often"),
    ("unoccluded", "Near Lights",
     "The lights that light this point most (ignoring shadows) more often"),
    ("tree", "Light Tree", "Lights chosen through a light hierarchy by their likely "
                           "contribution (fast with many lights)"),
    ("defensive", "Near or Any",
     "Half the time the lights that light this point most (ignoring shadows), half the "
     "time any light (defensive mixture; with a world, nine times in ten the former)"),
)
_SAMPLERS = (  # SPEC name, label, tooltip end
    ("area", "Area", "a point on the light's area"),
    ("solid-angle", "Angle", "a direction inside the light's visible outline"),
    ("parallel", "Projected",
     "a point of its outline as seen from the surface (parallel projection)"),
    ("projected-solid-angle", "Cosine",
     "a direction inside its visible outline, more often where the light falls "
     "steeply on the surface (projected solid angle)"),
)
TECHNIQUES = (
    ("BSDF", "bsdf", "Surface Directions",
     "Directions the surface scatters into (cosine-weighted BSDF sampling, 'bsdf'); "
     "best for big, soft lights and the sky"),
) + tuple(
    (f"{sel.upper()}_{smp.upper().replace('-', '_')}", f"{sel}/{smp}",
     f"{sel_label} · {smp_label}", f"{sel_tip}, {smp_tip} ('{sel}/{smp}')")
    for sel, sel_label, sel_tip in _SELECTIONS for smp, smp_label, smp_tip in _SAMPLERS)
TECHNIQUE_NAME = {ident: name for ident, name, _, _ in TECHNIQUES}
TECHNIQUE_ID = {name: ident for ident, name, _, _ in TECHNIQUES}

HEURISTICS = ("BALANCE", "POWER", "MAXIMUM", "CUTOFF")

# Blender's own bake settings (scene.render.bake) that omis honours or refuses; the
# operator and bake() take them as arguments like bpy.ops.object.bake does, and an
# unset one comes from the scene. Blender's 'VERTEX_COLORS' target is omis'
# 'COLOR_ATTRIBUTES'.
OUTPUT_NAMES = ("target", "margin", "margin_type", "use_clear", "use_selected_to_active")
TARGET_ALIASES = {'VERTEX_COLORS': 'COLOR_ATTRIBUTES'}


def _props():
    """Fresh bpy.props definitions of omis' own settings (`scene.omis`), name -> property
    (a new set per owner class). Labels in an artist's words; the research names
    (SPEC §1–3) in the tooltips."""
    return {
        "use_optimal_mis": BoolProperty(
            name="Least Noise", default=True,
            description="Blend the sampling methods with the weights that give the least "
                        "noise for the samples taken (optimal multiple importance sampling, "
                        "Kondapaneni et al. 2019); off: a fixed blending rule (MIS heuristic)"),
        "optimal_mode": EnumProperty(
            name="Weights", default='DIRECT',
            description="When the least-noise weights are worked out",
            items=(('DIRECT', "From All Samples",
                    "Once, from all samples of a texel: least noise; a tiny bias that "
                    "vanishes as samples grow ('optimal-direct')"),
                   ('PROGRESSIVE', "Pass by Pass",
                    "Anew after each pass, from the earlier passes: no bias, a little more "
                    "noise ('optimal-progressive')"))),
        "heuristic": EnumProperty(
            name="Blending", default='BALANCE',
            description="How the sampling methods are blended when Least Noise is off "
                        "(MIS heuristic)",
            items=(('BALANCE', "Balance", "By each method's density (balance heuristic)"),
                   ('POWER', "Power", "By each method's density raised to Beta (power "
                                      "heuristic)"),
                   ('MAXIMUM', "Maximum", "All to the method of highest density (maximum "
                                          "heuristic)"),
                   ('CUTOFF', "Cutoff", "Balance over the methods above Cutoff × the "
                                        "largest density (cutoff heuristic)"))),
        "power_beta": FloatProperty(
            name="Beta", default=2.0, min=0.1, max=16.0,
            description="Exponent of the power heuristic"),
        "cutoff_threshold": FloatProperty(
            name="Cutoff", default=0.1, min=0.0, max=1.0,
            description="Relative density below which the cutoff heuristic drops a method"),
        "technique_mode": EnumProperty(
            name="Sampling", default='AUTO',
            description="Which sampling methods (MIS techniques) look for the light",
            items=(('AUTO', "Automatic", "Chosen for the scene's lights and emitters (the "
                                         "effect plan), with sample counts"),
                   ('MANUAL', "Manual", "The methods ticked below, one sample each per "
                                        "round"))),
        "techniques": EnumProperty(
            name="Sampling Methods", options={'ENUM_FLAG'},
            default={'BSDF', 'UNOCCLUDED_SOLID_ANGLE'},
            description="Sampling methods (MIS techniques) blended together (Manual "
                        "sampling); giving them to the operator or to omis_bake.bake() "
                        "implies Manual",
            items=tuple((ident, label, desc, 1 << i)
                        for i, (ident, _, label, desc) in enumerate(TECHNIQUES))),
        "samples": IntProperty(
            name="Samples", default=128, min=1, soft_max=4096,
            description="Samples per texel (or vertex): the sample budget"),
        "time_budget": FloatProperty(
            name="Time Limit", default=0.0, min=0.0, soft_max=600.0, subtype='TIME_ABSOLUTE',
            unit='TIME_ABSOLUTE',
            description="Stop after this many seconds for the whole bake (0: no limit)"),
        "use_noise_target": BoolProperty(
            name="Noise Limit", default=False,
            description="Stop sampling a texel once its estimated noise (relative standard "
                        "error) is below the limit (a noise threshold)"),
        "noise_target": FloatProperty(
            name="Noise Limit", default=0.01, min=0.0001, max=1.0, precision=4,
            description="Noise (relative standard error) at which a texel is done: 0.01 "
                        "means ±1 % (a noise threshold)"),
        "seed": IntProperty(
            name="Seed", default=0, min=0,
            description="Random seed: the same seed and settings give the same bake"),
    }


def _output_props():
    """Operator arguments mirroring scene.render.bake (never stored in scene.omis)."""
    return {
        "target": EnumProperty(
            name="Target", default='IMAGE_TEXTURES',
            description="Where to bake (default: Render Properties ▸ Bake ▸ Output ▸ Target)",
            items=(('IMAGE_TEXTURES', "Image Textures",
                    "Bake into the image of each material's active Image Texture node"),
                   ('VERTEX_COLORS', "Active Color Attribute",
                    "Bake into the mesh's active color attribute"),
                   ('COLOR_ATTRIBUTES', "Color Attributes",
                    "Same as Active Color Attribute (omis' earlier name)"))),
        "margin": IntProperty(
            name="Margin", default=16, min=0, soft_max=64, subtype='PIXEL',
            description="Extend the baked result as a post process filter (pixels; default: "
                        "Render Properties ▸ Bake ▸ Margin ▸ Size)"),
        "margin_type": EnumProperty(
            name="Margin Type", default='ADJACENT_FACES',
            description="Which values fill the margin (default: Render Properties ▸ Bake ▸ "
                        "Margin ▸ Type)",
            items=(('ADJACENT_FACES', "Adjacent Faces", "Use pixels from adjacent faces "
                                                         "across UV seams"),
                   ('EXTEND', "Extend", "Extend border pixels outwards"))),
        "use_clear": BoolProperty(
            name="Clear Image", default=True,
            description="Clear the images before baking (default: Render Properties ▸ Bake ▸ "
                        "Output ▸ Clear Image)"),
        "use_selected_to_active": BoolProperty(
            name="Selected to Active", default=False,
            description="Bake the selected objects onto the active one (not supported: "
                        "refused with a message)"),
    }


# Shown after a bake; not operator arguments (see README: the bake's statistics).
# (name, property type, label, description); every default is the type's zero.
_RESULTS = (
    ("last_status", StringProperty, "Last Status", "How the last bake ended"),
    ("last_seconds", FloatProperty, "Last Time", "Seconds the last bake took, end to end"),
    ("last_samples_per_texel", FloatProperty, "Last Samples per Texel",
     "Mean samples per baked texel (or corner) of the last bake"),
    ("last_mean_error", FloatProperty, "Last Mean Error",
     "Mean over the baked texels of the estimated relative error (standard error / value) "
     "of the last bake"),
    ("last_error_p95", FloatProperty, "Last Error (95th percentile)",
     "95 % of the baked texels had at most this relative error"),
    ("last_halving_seconds", FloatProperty, "Last Halving Time",
     "Extra seconds of sampling that would halve the mean error: estimated from the bake's "
     "measured convergence (passes taken under a time limit or noise threshold), else an "
     "upper bound from the 1/√time rate"),
    ("last_halving_measured", BoolProperty, "Last Halving Time Measured",
     "Whether the halving time comes from the last bake's measured convergence (else it is "
     "the 1/√time upper bound)"),
    ("last_error_measured", BoolProperty, "Last Error Measured",
     "Whether the last bake's error was measured (a noise threshold: independently scrambled "
     "streams per texel) or is an upper estimate (one scrambled sequence per texel, the least "
     "noise: its error computed as for independent samples)"),
    ("last_plan", StringProperty, "Last Sampling Plan",
     "The sampling methods and sample counts chosen (the effect plan)"),
    ("last_target", StringProperty, "Last Target",
     "What the last bake wrote: 'IMAGE_TEXTURES' (texels) or 'COLOR_ATTRIBUTES' (vertices)"),
    ("last_warnings", StringProperty, "Last Warnings",
     "What the last bake ignored or did differently from Cycles, one warning per line"),
    ("show_all_warnings", BoolProperty, "Show All Warnings",
     "List every warning of the last bake, not only the first ones"),
)


def _result_props():
    return {name: kind(name=label, description=text) for name, kind, label, text in _RESULTS}


SETTING_NAMES = tuple(_props().keys())
ARGUMENT_NAMES = SETTING_NAMES + OUTPUT_NAMES


@dataclass
class Settings:
    """Plain-Python copy of the settings: safe to use off the main thread."""
    use_optimal_mis: bool = True
    optimal_mode: str = 'DIRECT'
    heuristic: str = 'BALANCE'
    power_beta: float = 2.0
    cutoff_threshold: float = 0.1
    technique_mode: str = 'AUTO'
    techniques: frozenset = frozenset({'BSDF', 'UNOCCLUDED_SOLID_ANGLE'})
    samples: int = 128
    time_budget: float = 0.0
    use_noise_target: bool = False
    noise_target: float = 0.01
    seed: int = 0
    # From scene.render.bake (or an operator / bake() argument):
    target: str = 'IMAGE_TEXTURES'
    margin: int = 16
    margin_type: str = 'ADJACENT_FACES'
    use_clear: bool = True
    use_selected_to_active: bool = False

    @property
    def strategy(self):
        """The omis strategy name (SPEC §1–2)."""
        if self.use_optimal_mis:
            return "optimal-direct" if self.optimal_mode == 'DIRECT' else "optimal-progressive"
        return self.heuristic.lower()

    def technique_names(self):
        """SPEC §3 names in the fixed order, or None for the effect plan's choice."""
        if self.technique_mode == 'AUTO':
            return None
        return [name for ident, name, _, _ in TECHNIQUES if ident in self.techniques]

    def check(self):
        """Raises ValueError naming the first unusable setting."""
        enums = {"optimal_mode": ('DIRECT', 'PROGRESSIVE'), "heuristic": HEURISTICS,
                 "technique_mode": ('AUTO', 'MANUAL'),
                 "target": ('IMAGE_TEXTURES', 'COLOR_ATTRIBUTES'),
                 "margin_type": ('EXTEND', 'ADJACENT_FACES')}
        for name, allowed in enums.items():
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name}: expected one of {', '.join(allowed)}, "
                                 f"got {getattr(self, name)!r}")
        unknown = set(self.techniques) - set(TECHNIQUE_NAME)
        if unknown:
            raise ValueError(f"techniques: unknown {', '.join(sorted(unknown))} (use "
                             f"{', '.join(TECHNIQUE_NAME)} or the SPEC names)")
        if self.technique_mode == 'MANUAL' and not self.techniques:
            raise ValueError("techniques: Manual mode needs at least one technique")
        if int(self.samples) < 1:
            raise ValueError("samples: must be at least 1")
        if not float(self.time_budget) >= 0:
            raise ValueError("time_budget: must be ≥ 0 seconds (0 = no limit)")
        if self.use_noise_target and not float(self.noise_target) > 0:
            raise ValueError("noise_target: must be > 0")
        if int(self.margin) < 0:
            raise ValueError("margin: must not be negative")
        if int(self.seed) < 0:
            raise ValueError("seed: must not be negative")

    def unsupported(self):
        """Why omis cannot bake what Blender's bake settings ask for, or None. These
        are refused rather than silently baked differently."""
        if self.use_selected_to_active:
            return ("Selected to Active is not supported by omis: untick Render Properties ▸ "
                    "Bake ▸ Selected to Active (scene.render.bake.use_selected_to_active = "
                    "False, or use_selected_to_active=False), or use Cycles' own Bake for it")
        return None


def _normalise_techniques(value):
    """Accepts identifiers ('BSDF') or SPEC names ('bsdf', 'unoccluded/solid-angle')."""
    if isinstance(value, str):
        value = [value]
    out = set()
    for item in value:
        item = str(item)
        out.add(TECHNIQUE_ID.get(item, item))
    return frozenset(out)


def _blender_bake_settings(source):
    """scene.render.bake of the scene owning `source` (scene.omis), or None."""
    scene = getattr(source, "id_data", None)
    render = getattr(scene, "render", None)
    return getattr(render, "bake", None)


def settings_from(source, overrides=None):
    """Settings from scene.omis and the scene's own bake settings (scene.render.bake),
    with overrides applied.

    overrides: a dict name -> value; unknown names raise TypeError like a bad
    keyword argument would. Giving techniques without technique_mode implies
    technique_mode='MANUAL' (so the operator, bake() and the panel agree).
    """
    overrides = dict(overrides or {})
    values = {}
    for name in SETTING_NAMES:
        v = getattr(source, name)
        values[name] = frozenset(v) if name == "techniques" else v
    blender = _blender_bake_settings(source)
    defaults = Settings()
    for name in OUTPUT_NAMES:
        values[name] = getattr(blender, name) if blender is not None else getattr(defaults, name)
    for name, value in overrides.items():
        if name not in values:
            raise TypeError(f"unknown setting {name!r} (known: {', '.join(ARGUMENT_NAMES)})")
        values[name] = _normalise_techniques(value) if name == "techniques" else value
    if "techniques" in overrides and "technique_mode" not in overrides:
        values["technique_mode"] = 'MANUAL'
    values["target"] = TARGET_ALIASES.get(values["target"], values["target"])
    s = Settings(**values)
    s.check()
    return s


class OMIS_PG_settings(bpy.types.PropertyGroup):
    """omis bake settings of a scene (`scene.omis`)."""


OMIS_PG_settings.__annotations__ = {**_props(), **_result_props()}


def operator_annotations():
    """Operator arguments: every setting and Blender's bake output settings, as SKIP_SAVE
    so an unset one means 'the scene's'."""
    out = {}
    for name, prop in {**_props(), **_output_props()}.items():
        # bpy.props return a deferred (function, keywords) pair; add SKIP_SAVE.
        function, keywords = prop.function, dict(prop.keywords)
        options = set(keywords.get("options", set())) | {'SKIP_SAVE'}
        keywords["options"] = options
        out[name] = function(**keywords)
    return out
