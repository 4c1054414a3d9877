"""Optimal MIS against the balance heuristic on an image-based world seen
through a window: a closed 4 × 4 × 3 m room whose only opening is a 1.2 × 1 m
window, under a procedural sky (a blue gradient and a 0.5° sun ~7 times the
sky's irradiance on a horizontal plane) whose sun shines through the window
onto the floor. The floor is sampled at a grid of points facing up.

For each technique set and strategy: relMSE of E/π over the floor points
against a long reference (mean over points of (x − r)²/(r² + ε²), grey = mean
of RGB, ε = 0.01·mean(r)), averaged over seeds, and the CPU time of the runs
(wall time on a loaded machine: compare ratios within one run).

Usage: PYTHONPATH=build/python python3 bench/bench_world_window.py [--seeds 8]
       [--samples 16] [--grid 24]
"""
import argparse
import time

import numpy as np

import omis
from omis import demo


def quad(a, b, c, d):
    return [a, b, c, d], [[0, 1, 2], [0, 2, 3]]


def window_room(scene):
    """Walls, floor and ceiling facing inward; the +X wall has a window at
    y in [-0.6, 0.6], z in [1, 2]."""
    x0, x1, y0, y1, z0, z1 = -2.0, 2.0, -2.0, 2.0, 0.0, 3.0
    wy0, wy1, wz0, wz1 = -0.6, 0.6, 1.0, 2.0
    quads = [
        quad((x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)),  # floor
        quad((x0, y0, z1), (x0, y1, z1), (x1, y1, z1), (x1, y0, z1)),  # ceiling
        quad((x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)),  # -X wall
        quad((x0, y0, z0), (x0, y0, z1), (x1, y0, z1), (x1, y0, z0)),  # -Y wall
        quad((x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)),  # +Y wall
        # +X wall around the window
        quad((x1, y0, z0), (x1, y0, wz0), (x1, y1, wz0), (x1, y1, z0)),
        quad((x1, y0, wz1), (x1, y0, z1), (x1, y1, z1), (x1, y1, wz1)),
        quad((x1, y0, wz0), (x1, y0, wz1), (x1, wy0, wz1), (x1, wy0, wz0)),
        quad((x1, wy1, wz0), (x1, wy1, wz1), (x1, y1, wz1), (x1, y1, wz0)),
    ]
    for verts, tris in quads:
        scene.add_mesh(np.array(verts, float), np.array(tris))


def floor_points(grid):
    s = (np.arange(grid) + 0.5) / grid * 3.8 - 1.9
    xs, ys = np.meshgrid(s, s)
    points = np.stack([xs.ravel(), ys.ravel(), np.full(xs.size, 1e-3)], axis=1)
    return points, np.tile([0.0, 0.0, 1.0], (len(points), 1))


def rel_mse(x, ref):
    g, r = x.mean(axis=1), ref.mean(axis=1)
    eps = 0.01 * r.mean()
    return float(np.mean((g - r) ** 2 / (r ** 2 + eps ** 2)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--samples", type=int, default=16, help="per technique per point")
    ap.add_argument("--grid", type=int, default=24)
    ap.add_argument("--reference-samples", type=int, default=4096)
    ap.add_argument("--open", action="store_true", help="no room: the floor under the open sky")
    args = ap.parse_args()
    image, sun = demo.sky()
    points, normals = floor_points(args.grid)
    scenes = {}
    for compensate in (False, True):
        scene = omis.Scene()
        if not args.open:
            window_room(scene)
        scene.set_world_image(image, compensate=compensate)
        scene.commit()
        scenes[compensate] = scene
    n, r = args.samples, args.reference_samples
    ref, _ = omis.direct_lighting(scenes[False], points, normals, ["uniform/solid-angle", "bsdf"],
                                  [1, 1], rounds=r, strategy="balance", seed=999)
    print(f"{'open sky' if args.open else 'window room'}: {len(points)} floor points, {n} rounds of 1+1 draws, {args.seeds} seeds, "
          f"reference {r} rounds (balance); sun direction {np.round(sun, 3).tolist()}")
    print(f"{'techniques':34s} {'compensated':>11s} {'strategy':>15s} {'relMSE':>10s} "
          f"{'time s':>8s} {'relMSE x time':>14s}")
    # One draw of each technique a round, n rounds (the plan's default and what a
    # bake does): optimal-direct solves over all rounds, cross-fitted.
    sets = [(["uniform/solid-angle", "bsdf"], [1, 1]), (["uniform/solid-angle"], [2]),
            (["bsdf"], [2])]
    rows = []
    for names, samples in sets:
        for compensate in (False, True):
            if compensate and names != ["uniform/solid-angle", "bsdf"]:
                continue  # refused without bsdf; no map draws to compensate with bsdf alone
            for strategy in ("balance", "optimal-direct"):
                errs, elapsed = [], 0.0
                for seed in range(args.seeds):
                    t0 = time.process_time()
                    v, _ = omis.direct_lighting(scenes[compensate], points, normals, names,
                                                samples, rounds=n, strategy=strategy,
                                                seed=seed + 1)
                    elapsed += time.process_time() - t0
                    errs.append(rel_mse(v, ref))
                e = float(np.mean(errs))
                rows.append((names, compensate, strategy, e, elapsed))
                print(f"{' + '.join(names):34s} {str(compensate):>11s} {strategy:>15s} "
                      f"{e:10.4g} {elapsed:8.2f} {e * elapsed:14.4g}")
    return rows


if __name__ == "__main__":
    main()
