"""Error per sample of texel bakes among many emitters (issue 8): which techniques the
effect plan should use. Load-independent: the relative variance of each texel over
independent seeds at a fixed sample count, not a time.

    PYTHONPATH=build/python /usr/bin/python3 bench/bench_emitters_quality.py
        [--scenes emissive_mesh,many_lights,panel_near,sphere_near] [--samples 32]
        [--seeds 8] [--size 48] [--techniques "plan;tree/solid-angle,bsdf;..."]

Scenes (a 2 m floor, baked at size² texels):
- emissive_mesh: bench_cycles' race scene (tests/blender/cycles_scenes.py): a UV sphere
  of 128 × 64 segments (16,128 emissive triangles) and a 0.3 m square light above it;
- many_lights: cycles_scenes' many_lights grid (squares, disks, sphere, delta point
  and spot lights) and its occluding box;
- panel_near: a coarse emissive sphere 5 cm above the floor and a 1.6 m emissive panel
  of 32 triangles 25 cm above it (emitters covering much of the hemisphere);
- sphere_near: a 32 × 16 emissive UV sphere 5 cm above the floor.

Per scene and technique set (`plan`: the effect plan's choice), strategies balance and
optimal-direct: relvar = mean over texels of Var/(mean² + ε²) (ε = 1 % of the mean,
as bench_cycles' relMSE), relvar·spp (error per sample: lower is better) and the CPU
seconds of all bakes (process time, all threads: only comparable within one run).
"""

import argparse
import math
import time

import numpy as np

import omis
from omis import blender_units as U
from omis import demo


def uv_sphere(segments, rings, radius, centre):
    """Blender's UV sphere: poles, fans at the poles, quads split in two; outward."""
    c = np.asarray(centre, float)
    verts = [c + [0, 0, radius]]
    for r in range(1, rings):
        th = math.pi * r / rings
        for s in range(segments):
            ph = 2 * math.pi * s / segments
            verts.append(c + radius * np.array([math.sin(th) * math.cos(ph),
                                                math.sin(th) * math.sin(ph), math.cos(th)]))
    verts.append(c - [0, 0, radius])
    bottom = len(verts) - 1

    def ring(r, s):
        return 1 + (r - 1) * segments + s % segments
    tris = []
    for s in range(segments):
        tris += [(0, ring(1, s), ring(1, s + 1)), (bottom, ring(rings - 1, s + 1), ring(rings - 1, s))]
    for r in range(1, rings - 1):
        for s in range(segments):
            a, b, c2, d = ring(r, s), ring(r, s + 1), ring(r + 1, s), ring(r + 1, s + 1)
            tris += [(a, c2, d), (a, d, b)]
    return np.array(verts), np.array(tris, np.uint32)


def emissive_mesh(scene):
    v, t = uv_sphere(128, 64, 0.3, (0.2, 0.1, 0.6))
    scene.add_mesh(v, t, emission=U.mesh_emission(3.0, (1.0, 0.85, 0.7)))
    a = U.area_light(40.0, (1, 1, 1), 'SQUARE', 0.3)
    # 0.3 m square about (0.35, 0.2, 1.4), emitting down (cross(edge_u, edge_v) = −z).
    scene.add_rect_light(corner=(0.2, 0.05, 1.4), edge_u=(0, 0.3, 0), edge_v=(0.3, 0, 0),
                         radiance=a.radiance)


def many_lights(scene):
    kinds = ('SQUARE', 'DISK', 'POINT', 'POINT_DELTA', 'SPOT')
    for j in range(8):
        for i in range(8):
            k = kinds[(i + 3 * j) % len(kinds)]
            p = np.array([-0.9 + i * (1.8 / 7), -0.9 + j * (1.8 / 7),
                          0.5 + 0.08 * ((i * 5 + j * 3) % 7)])
            color = (1.0, 0.6 + 0.05 * i, 0.4 + 0.07 * j)
            a, b = math.radians(10 * (i - 4)), math.radians(8 * (j - 4))
            n = np.array([-math.sin(b), math.sin(a), -math.cos(a) * math.cos(b)])
            n /= np.linalg.norm(n)
            if k == 'SQUARE':
                u = U.area_light(3.0 + (i + j) % 4, color, 'SQUARE', 0.15)
                eu = np.cross(n, [0, 1, 0])
                eu *= 0.15 / np.linalg.norm(eu)
                ev = np.cross(n, eu)  # cross(eu, ev) = n: emits along n
                scene.add_rect_light(corner=tuple(p - 0.5 * (eu + ev)), edge_u=tuple(eu),
                                     edge_v=tuple(ev), radiance=u.radiance)
            elif k == 'DISK':
                u = U.area_light(3.0 + (i + j) % 4, color, 'DISK', 0.15)
                scene.add_disk_light(center=tuple(p), normal=tuple(n), radius=0.075,
                                     radiance=u.radiance)
            elif k == 'SPOT':
                u = U.spot_light(6.0, color, math.radians(70), 0.2)
                scene.add_spot_light(position=tuple(p), intensity=u.intensity,
                                     direction=(0, math.sin(math.radians(12)), -math.cos(math.radians(12))),
                                     spot_size=math.radians(70), spot_blend=0.2)
            else:
                r = 0.05 if k == 'POINT' else 0.0
                scene.add_point_light(position=tuple(p), intensity=U.point_light(2.0, color, r).intensity,
                                      radius=r)
    scene.add_mesh(*demo.box((0.1, -0.1, 0.3), (0.5, 0.3, 0.05)))


def panel_near(scene):
    v, t = uv_sphere(16, 8, 0.4, (0.4, 0.4, 0.45))
    scene.add_mesh(v, t, emission=(2.0, 2.0, 2.0))
    pv, pt, _ = demo.grid(1.6, 1.6, 4, z=0.25)
    scene.add_mesh(pv + np.array([-0.5, -0.5, 0]), pt, emission=(1.0, 1.0, 1.0))


def sphere_near(scene):
    v, t = uv_sphere(32, 16, 0.4, (0.2, 0.1, 0.45))
    scene.add_mesh(v, t, emission=(2.0, 2.0, 2.0))


SCENES = dict(emissive_mesh=emissive_mesh, many_lights=many_lights, panel_near=panel_near,
              sphere_near=sphere_near)


def measure(scene, floor, size, samples, seeds, strategy, techniques):
    kw = {} if techniques is None else dict(techniques=techniques)
    values, spp = [], 0.0
    start = time.process_time()
    for seed in range(seeds):
        r = omis.bake_uv(scene, floor, size, size, samples=samples, strategy=strategy,
                         seed=seed, margin=0, **kw)
        values.append(np.asarray(r.value)[..., :3].mean(-1).ravel())
        spp = r.stats["samples_per_texel"]
    cpu = time.process_time() - start
    v = np.array(values)
    mean = v.mean(0)
    eps2 = (0.01 * mean.mean()) ** 2
    return float(np.mean(v.var(0, ddof=1) / (mean * mean + eps2))), spp, cpu


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--scenes", default=",".join(SCENES))
    parser.add_argument("--samples", type=int, default=32)
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--size", type=int, default=48)
    parser.add_argument("--techniques", default="plan",
                        help="technique sets separated by ';', each comma-separated; plan = "
                             "the effect plan's")
    args = parser.parse_args()
    sets = [None if s == "plan" else s.split(",") for s in args.techniques.split(";")]
    print(f"relative variance over {args.seeds} seeds, {args.size}² texels, "
          f"{args.samples} samples per texel")
    print(f"{'scene':<14} {'techniques':<42} {'strategy':<15} {'spp':>4} {'relvar':>9} "
          f"{'relvar·spp':>10} {'CPU s':>6}")
    for name in args.scenes.split(","):
        scene = omis.Scene()
        fv, ft, fuv = demo.grid(2.0, 2.0, 2)
        floor = scene.add_mesh(fv, ft, uvs=fuv)
        SCENES[name](scene)
        scene.commit()
        for techniques in sets:
            label = ("plan: " + "+".join(
                line.split()[1] for line in scene.effect_plan().splitlines()
                if line.strip().startswith("+ "))) if techniques is None else "+".join(techniques)
            for strategy in ("balance", "optimal-direct"):
                rel, spp, cpu = measure(scene, floor, args.size, args.samples, args.seeds,
                                        strategy, techniques)
                print(f"{name:<14} {label:<42} {strategy:<15} {spp:>4.0f} {rel:>9.3e} "
                      f"{rel * spp:>10.3e} {cpu:>6.2f}", flush=True)


if __name__ == "__main__":
    main()
