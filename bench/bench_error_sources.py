"""Where the error of a bake comes from: omis against Cycles at equal samples, per region.

    bash scripts/blender_run.sh bench/bench_error_sources.py [--out DIR]
        [--scenes shared_image,demo_room] [--spp 64,256] [--seeds 3] [--ref-spp 2048]
        [--size 128]

For each scene (those of bench/bench_cycles.py) and sample count: Cycles' own
bake and omis optimal-direct (a sample budget, the effect plan's techniques),
each over `--seeds` seeds, against its own renderer's reference (the mean of
two bakes at --ref-spp, whose difference gives the reference's own noise,
subtracted as bench_cycles does). relMSE per texel = mean over seeds of
(x − r)² / (r² + ε²), ε = 1 % of the mean, over covered interior texels.

The texels fall into regions by the Cycles reference r (mean m) and its
relative gradient g = |∇r| / (r + 0.05 m):
  dark    r < 0.05 m     (fully shadowed but for a little light)
  dim     0.05 m ≤ r < 0.3 m
  edge    r ≥ 0.3 m, g > 0.05 per texel (penumbrae)
  smooth  the rest
  border  covered interior texels next to the island's edge texels (seams)
and each region's share of the scene's relMSE and mean relMSE are printed for
both renderers with their ratio. Writes DIR/error_sources.txt and, per scene
and sample count, DIR/<scene>_<spp>.png (reference, both error maps, their
log2 ratio).
"""

import argparse
import os
import sys

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
import omis_test_utils as U  # noqa: E402
import cycles_scenes  # noqa: E402

from omis_bake.job import BakeJob  # noqa: E402
from omis_bake.settings import settings_from  # noqa: E402


SCENES = dict(cycles_scenes.SCENES)
SCENES["demo_room"] = U.demo_room


def grey(image):
    return U.pixels(image)[..., :3].astype(np.float64).mean(axis=2)


def cycles_bake(objects, image, spp, seed):
    U.set_pixels(image, (0.0, 0.0, 0.0, 0.0))
    U.cycles_bake(objects, int(spp), seed)
    return grey(image)


def omis_bake(objects, image, spp, seed, balance=False):
    """A sample budget of spp per texel; returns the image and the covered mask."""
    U.set_pixels(image, (0.0, 0.0, 0.0, 0.0))
    U.select_only(objects)
    overrides = {"samples": int(spp), "time_budget": 0.0, "margin": 0, "seed": int(seed),
                 "use_noise_target": False, "technique_mode": 'AUTO', "use_clear": True}
    if balance:
        overrides.update(use_optimal_mis=False, heuristic='BALANCE')
    else:
        overrides.update(use_optimal_mis=True, optimal_mode='DIRECT')
    job = BakeJob(bpy.context, objects, settings_from(bpy.context.scene.omis, overrides))
    job.run()
    stats = job.finish(bpy.context)
    mask = np.zeros((image.size[1], image.size[0]), bool)
    for unit in job.units:
        mask |= unit.mask > 0.5
    return grey(image), mask, stats


def regions(reference, inside):
    mean = reference[inside].mean()
    gy, gx = np.gradient(reference)
    gradient = np.hypot(gx, gy) / (reference + 0.05 * mean)
    lit = reference >= 0.3 * mean
    return {
        "dark": inside & (reference < 0.05 * mean),
        "dim": inside & (reference >= 0.05 * mean) & ~lit,
        "edge": inside & lit & (gradient > 0.05),
        "smooth": inside & lit & (gradient <= 0.05),
        "border": inside & ~U.interior_texels(inside),
    }


def relative_errors(runs, a, b, eps2):
    """Per texel: mean over runs of (x − r)² less the reference's own variance, / (r² + ε²)."""
    r = 0.5 * (a + b)
    own = 0.25 * (a - b) ** 2
    return (np.mean([(x - r) ** 2 for x in runs], axis=0) - own) / (r * r + eps2)


def plot(path, reference, cycles, omis, inside, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 4, figsize=(20, 5))
    ax[0].imshow(np.log10(reference + 1e-3 * reference[inside].mean()), origin="lower")
    ax[0].set_title(f"{title}: log10 reference")
    top = np.log10(max(cycles[inside].max(), omis[inside].max(), 1e-12))
    for a, e, name in ((ax[1], cycles, "Cycles"), (ax[2], omis, "omis optimal")):
        a.imshow(np.where(inside, np.log10(np.maximum(e, 1e-12)), np.nan), origin="lower",
                 vmin=top - 4, vmax=top)
        a.set_title(f"{name}: log10 relative squared error")
    ratio = np.log2(np.maximum(omis, 1e-12) / np.maximum(cycles, 1e-12))
    im = ax[3].imshow(np.where(inside, ratio, np.nan), origin="lower", vmin=-2, vmax=2,
                      cmap="RdBu_r")
    ax[3].set_title("log2 omis / Cycles")
    fig.colorbar(im, ax=ax[3])
    fig.savefig(path, dpi=60)
    plt.close(fig)


def run_scene(name, args, lines):
    U.reset_scene()
    objects = SCENES[name](args.size)
    bpy.context.view_layer.update()
    (image,) = cycles_scenes.images_of(objects)
    _, cover, stats = omis_bake(objects, image, 1, 1, balance=True)
    inside = U.interior_texels(cover)
    ca = cycles_bake(objects, image, args.ref_spp, 1001)
    cb = cycles_bake(objects, image, args.ref_spp, 1002)
    oa, _, _ = omis_bake(objects, image, args.ref_spp, 2001, balance=True)
    ob, _, _ = omis_bake(objects, image, args.ref_spp, 2002, balance=True)
    reference = 0.5 * (ca + cb)
    eps2 = (0.01 * reference[inside].mean()) ** 2
    parts = regions(reference, inside)
    plan = [line.strip() for line in (stats["plan"] or "").splitlines()
            if line.strip().startswith(("+ ", "- "))]
    lines.append(f"== {name}: {int(inside.sum())} texels; plan {'; '.join(plan) or '-'}")
    for spp in args.spp:
        cycles_runs = [cycles_bake(objects, image, spp, 10 + s) for s in range(args.seeds)]
        omis_runs = [omis_bake(objects, image, spp, 20 + s)[0] for s in range(args.seeds)]
        c = relative_errors(cycles_runs, ca, cb, eps2)
        o = relative_errors(omis_runs, oa, ob, eps2)
        lines.append(f"  {spp} spp: relMSE Cycles {c[inside].mean():.3e}, omis "
                     f"{o[inside].mean():.3e}, omis / Cycles {o[inside].mean() / c[inside].mean():.2f}")
        for region, where in parts.items():
            if not where.any():
                continue
            lines.append(
                f"    {region:<7} {int(where.sum()):6d} texels  share of relMSE: Cycles "
                f"{c[where].sum() / c[inside].sum():4.2f}, omis {o[where].sum() / o[inside].sum():4.2f};"
                f"  mean: Cycles {c[where].mean():.2e}, omis {o[where].mean():.2e}"
                f" ({o[where].mean() / max(c[where].mean(), 1e-300):.2f})")
        plot(os.path.join(args.out, f"{name}_{spp}.png"), reference, c, o, inside,
             f"{name} {spp} spp")
        U.log("\n".join(lines[-1 - len(parts):]))


def main():
    parser = argparse.ArgumentParser(prog="bench_error_sources.py",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/bench_error_sources")
    parser.add_argument("--scenes", default="shared_image,demo_room")
    parser.add_argument("--spp", default="64,256")
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--ref-spp", type=int, default=2048)
    parser.add_argument("--size", type=int, default=128)
    args = parser.parse_args(U.args())
    args.spp = [int(n) for n in args.spp.split(",")]
    args.out = os.path.abspath(args.out)
    os.makedirs(args.out, exist_ok=True)
    lines = [f"bench_error_sources: {args.size}² images, {args.seeds} seeds, references "
             f"2×{args.ref_spp} spp"]
    for name in args.scenes.split(","):
        if name not in SCENES:
            raise SystemExit(f"unknown scene {name!r}; known: {', '.join(SCENES)}")
        run_scene(name, args, lines)
    text = "\n".join(lines)
    U.log("\n" + text)
    with open(os.path.join(args.out, "error_sources.txt"), "w") as f:
        f.write(text + "\n")


main()
