"""The bake settings: one table feeding the scene's PropertyGroup (`scene.omis`),
the operator's arguments (`bpy.ops.omis.bake(...)`) and the scripting call
(`omis_bake.bake(context, **settings)`), so the three never drift apart."""

from dataclasses import dataclass, fields

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

# Technique identifiers (Blender style) and their SPEC §3 names, in a fixed order.
TECHNIQUES = (
    ("BSDF", "bsdf", "BSDF", "Cosine-weighted hemisphere sampling"),
    ("UNIFORM_AREA", "uniform/area", "Uniform · Area",
     "Pick a light uniformly, sample its area"),
    ("UNIFORM_SOLID_ANGLE", "uniform/solid-angle", "Uniform · Solid Angle",
     "Pick a light uniformly, sample its solid angle"),
    ("UNIFORM_PARALLEL", "uniform/parallel", "Uniform · Parallel",
     "Pick a light uniformly, sample its parallel projection"),
    ("POWER_AREA", "power/area", "Power · Area",
     "Pick a light by emitted power, sample its area"),
    ("POWER_SOLID_ANGLE", "power/solid-angle", "Power · Solid Angle",
     "Pick a light by emitted power, sample its solid angle"),
    ("POWER_PARALLEL", "power/parallel", "Power · Parallel",
     "Pick a light by emitted power, sample its parallel projection"),
    ("UNOCCLUDED_AREA", "unoccluded/area", "Unoccluded · Area",
     "Pick a light by its unoccluded contribution at the point, sample its area"),
    ("UNOCCLUDED_SOLID_ANGLE", "unoccluded/solid-angle", "Unoccluded · Solid Angle",
     "Pick a light by its unoccluded contribution at the point, sample its solid angle"),
    ("UNOCCLUDED_PARALLEL", "unoccluded/parallel", "Unoccluded · Parallel",
     "Pick a light by its unoccluded contribution at the point, sample its parallel "
     "projection"),
)
TECHNIQUE_NAME = {ident: name for ident, name, _, _ in TECHNIQUES}
TECHNIQUE_ID = {name: ident for ident, name, _, _ in TECHNIQUES}

HEURISTICS = ("BALANCE", "POWER", "MAXIMUM", "CUTOFF")


def _props():
    """Fresh bpy.props definitions, name -> property (a new set per owner class)."""
    return {
        "use_optimal_mis": BoolProperty(
            name="Optimal MIS", default=True,
            description="Combine the techniques with the optimal MIS weights (Kondapaneni et "
                        "al. 2019); off: use the heuristic below"),
        "optimal_mode": EnumProperty(
            name="Mode", default='DIRECT',
            items=(('DIRECT', "Direct", "Solve once from all samples (biased, consistent; "
                                        "lowest noise)"),
                   ('PROGRESSIVE', "Progressive", "Re-solve between rounds, weighting each "
                                                  "round with earlier ones (unbiased)"))),
        "heuristic": EnumProperty(
            name="Heuristic", default='BALANCE',
            description="MIS heuristic used when Optimal MIS is off",
            items=(('BALANCE', "Balance", "Veach's balance heuristic"),
                   ('POWER', "Power", "Power heuristic (exponent Beta)"),
                   ('MAXIMUM', "Maximum", "All weight to the technique of highest density"),
                   ('CUTOFF', "Cutoff", "Balance over techniques above Cutoff × the largest "
                                        "density"))),
        "power_beta": FloatProperty(
            name="Beta", default=2.0, min=0.1, max=16.0,
            description="Exponent of the power heuristic"),
        "cutoff_threshold": FloatProperty(
            name="Cutoff", default=0.1, min=0.0, max=1.0,
            description="Relative density below which the cutoff heuristic drops a technique"),
        "technique_mode": EnumProperty(
            name="Techniques", default='AUTO',
            items=(('AUTO', "Auto", "The scene's effect plan chooses the techniques"),
                   ('MANUAL', "Manual", "Use the techniques ticked below, one sample each "
                                        "per round"))),
        "techniques": EnumProperty(
            name="Technique Set", options={'ENUM_FLAG'},
            default={'BSDF', 'UNOCCLUDED_SOLID_ANGLE'},
            description="Sampling techniques combined by MIS (Manual mode)",
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
            name="Noise Target", default=False,
            description="Stop sampling a texel once its estimated relative error is below "
                        "the target"),
        "noise_target": FloatProperty(
            name="Noise Target", default=0.01, min=0.0001, max=1.0, precision=4,
            description="Relative standard error at which a texel is done"),
        "target": EnumProperty(
            name="Target", default='IMAGE_TEXTURES',
            items=(('IMAGE_TEXTURES', "Image Textures",
                    "Bake into the image of each material's active Image Texture node"),
                   ('COLOR_ATTRIBUTES', "Color Attributes",
                    "Bake into the mesh's active color attribute"))),
        "margin": IntProperty(
            name="Margin", default=16, min=0, soft_max=64, subtype='PIXEL',
            description="Extend the baked result as a post process filter (pixels)"),
        "use_clear": BoolProperty(
            name="Clear Image", default=True,
            description="Clear the images before baking (else keep what is outside the "
                        "baked islands)"),
        "seed": IntProperty(
            name="Seed", default=0, min=0,
            description="Random seed: the same seed and settings give the same bake"),
    }


# Shown after a bake; not operator arguments.
def _result_props():
    return {
        "last_status": StringProperty(name="Last Status", default=""),
        "last_seconds": FloatProperty(name="Last Time", default=0.0),
        "last_samples_per_texel": FloatProperty(name="Last Samples per Texel", default=0.0),
        "last_mean_error": FloatProperty(name="Last Mean Relative Error", default=0.0),
        "last_plan": StringProperty(name="Last Effect Plan", default=""),
    }


SETTING_NAMES = tuple(_props().keys())


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
    target: str = 'IMAGE_TEXTURES'
    margin: int = 16
    use_clear: bool = True
    seed: int = 0

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
                 "target": ('IMAGE_TEXTURES', 'COLOR_ATTRIBUTES')}
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


def _normalise_techniques(value):
    """Accepts identifiers ('BSDF') or SPEC names ('bsdf', 'unoccluded/solid-angle')."""
    if isinstance(value, str):
        value = [value]
    out = set()
    for item in value:
        item = str(item)
        out.add(TECHNIQUE_ID.get(item, item))
    return frozenset(out)


def settings_from(source, overrides=None):
    """Settings from an RNA struct (scene.omis or an operator), with overrides applied.

    overrides: a dict name -> value; unknown names raise TypeError like a bad
    keyword argument would.
    """
    values = {}
    for f in fields(Settings):
        v = getattr(source, f.name)
        values[f.name] = frozenset(v) if f.name == "techniques" else v
    for name, value in (overrides or {}).items():
        if name not in values:
            raise TypeError(f"unknown setting {name!r} (known: {', '.join(SETTING_NAMES)})")
        values[name] = _normalise_techniques(value) if name == "techniques" else value
    s = Settings(**values)
    s.check()
    return s


class OMIS_PG_settings(bpy.types.PropertyGroup):
    """omis bake settings of a scene (`scene.omis`)."""


OMIS_PG_settings.__annotations__ = {**_props(), **_result_props()}


def operator_annotations():
    """Operator arguments: every setting, as SKIP_SAVE so an unset one means 'the scene's'."""
    out = {}
    for name, prop in _props().items():
        # bpy.props return a deferred (function, keywords) pair; add SKIP_SAVE.
        function, keywords = prop.function, dict(prop.keywords)
        options = set(keywords.get("options", set())) | {'SKIP_SAVE'}
        keywords["options"] = options
        out[name] = function(**keywords)
    return out
