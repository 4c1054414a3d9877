#!/usr/bin/env python3
"""Bake benchmark on the demo scene's floor (a printed table, not a test):

  1. throughput: texels/s of a 1024² lightmap per strategy at equal samples
  2. accuracy costs time: seconds to reach a noise target per strategy
  3. peak memory of a 1024² bake beyond its outputs
  4. speed-up from 1 to all threads (results are identical bits)

    PYTHONPATH=build/python python3 bench/bench_bake.py [--quick]

Figures are ratios measured in one run where possible: the machine is shared.
"""
import argparse
import subprocess
import sys
import time

import numpy as np

import omis
import omis.demo

STRATEGIES = ["balance", "power", "optimal-direct", "optimal-progressive"]


def bake(scene, floor, size, seed=3, **kw):
    return omis.bake_uv(scene, floor, size, size, seed=seed, **kw)


def throughput(scene, floor, size, spp):
    print(f"\n1. throughput: {size}² floor lightmap, {spp} samples/texel, all cores")
    print(f"   {'strategy':<22} {'seconds':>8} {'Mtexel·spp/s':>13} {'texels/s':>10} {'mean rel.err':>13}")
    rows = {}
    for s in STRATEGIES:
        r = bake(scene, floor, size, strategy=s, samples=spp)
        st = r.stats
        rate = st["covered"] / st["seconds"]
        rows[s] = st
        print(f"   {s:<22} {st['seconds']:>8.2f} {rate * spp / 1e6:>13.2f} {rate:>10.0f} "
              f"{100 * st['mean_relative_error']:>12.2f}%")
    b, o = rows["balance"], rows["optimal-direct"]
    print(f"   optimal-direct time per texel / balance: {o['seconds'] / b['seconds']:.3f}")
    return rows


def accuracy_costs_time(scene, floor, size, targets, cap, reference_spp):
    print(f"\n2. accuracy costs time: {size}² lightmap, seconds until every texel's estimated "
          f"relative standard error is below the target (cap {cap:g} s), and the true relative "
          f"RMS error then, against a {reference_spp}-sample reference")
    ref = bake(scene, floor, size, strategy="balance", samples=reference_spp, seed=12345).value[..., 1]
    lit = ref > 1e-3 * ref.max()
    header = "   " + f"{'strategy':<22}" + "".join(f"{'≤ %g %%' % (100 * t):>22}" for t in targets)
    print(header)
    table = {}
    for s in STRATEGIES:
        cells = []
        for t in targets:
            r = bake(scene, floor, size, strategy=s, samples=1 << 30, noise_target=t,
                     time_budget=cap)
            st = r.stats
            done = st["status"] == "noise target reached"
            err = np.sqrt(np.mean(((r.value[..., 1][lit] - ref[lit]) / ref[lit]) ** 2))
            est = np.sqrt(np.mean(r.noise[lit] ** 2))
            cells.append((st["seconds"], done, st["samples_per_texel"], err, est))
            table[(s, t)] = cells[-1]
        print("   " + f"{s:<22}" + "".join(
            f"{(('%.2f s' % sec) if ok else ('>%g s' % cap)) + (' (%.1f %%)' % (100 * e)):>22}"
            for sec, ok, _, e, _ in cells))
    print("   estimated / true relative RMS error (honest noise: within [0.8, 1.25]):")
    for s in STRATEGIES:
        print("   " + f"{s:<22}" + "".join(f"{table[(s, t)][4] / table[(s, t)][3]:>22.2f}"
                                         for t in targets))
    print("   true relative RMS error / target (a target stops at the error it names: "
          "within [0.8, 1]):")
    for s in STRATEGIES:
        print("   " + f"{s:<22}" + "".join(f"{table[(s, t)][3] / t:>22.2f}" for t in targets))
    print("   mean samples per texel spent:")
    for s in STRATEGIES:
        print("   " + f"{s:<22}" + "".join(f"{table[(s, t)][2]:>22.0f}" for t in targets))
    for t in targets:
        b, o = table[("balance", t)], table[("optimal-direct", t)]
        if b[1] and o[1]:
            print(f"   target {100 * t:g} %: optimal-direct takes {o[0] / b[0]:.2f}× the balance "
                  f"heuristic's time; true errors {100 * o[3]:.1f} % vs {100 * b[3]:.1f} %")
    return table


# Peak RSS from /proc (VmHWM, KiB): getrusage's ru_maxrss would carry the
# parent's peak across fork and exec on Linux and hide the child's own.
MEMORY_PROBE = r"""
import sys, omis, omis.demo
def peak():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
size, spp = int(sys.argv[1]), int(sys.argv[2])
scene, floor, _ = omis.demo.build_scene(omis)
before = peak()
r = omis.bake_uv(scene, floor, size, size, samples=spp)
after = peak()
print(before, after)
"""


def peak_memory(size, spp):
    out = subprocess.run([sys.executable, "-c", MEMORY_PROBE, str(size), str(spp)],
                         capture_output=True, text=True, check=True).stdout.split()
    before, after = (int(v) / 1024 for v in out)  # KiB → MiB
    outputs = size * size * (3 + 1 + 1) * 4 / 2 ** 20
    print(f"\n3. peak memory of a {size}² bake ({spp} samples/texel): peak RSS rose "
          f"{after - before:.1f} MiB; the outputs (value, noise, mask as float32) are "
          f"{outputs:.1f} MiB; beyond them {after - before - outputs:.1f} MiB (goal ≤ 64 MiB)")


def speedup(scene, floor, size, spp):
    one = bake(scene, floor, size, samples=spp, threads=1)
    all_ = bake(scene, floor, size, samples=spp)
    same = np.array_equal(one.value, all_.value)
    import os
    print(f"\n4. threads: 1 thread {one.stats['seconds']:.2f} s, all ({os.cpu_count()}) "
          f"{all_.stats['seconds']:.2f} s: speed-up {one.stats['seconds'] / all_.stats['seconds']:.2f}× "
          f"(goal ≥ 1.8× on 2 cores); identical bits: {same}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="small sizes, to check it runs")
    args = parser.parse_args()
    scene, floor, description = omis.demo.build_scene(omis)
    print(f"omis {omis.__version__} bake benchmark — demo scene: {description}")
    if args.quick:
        throughput(scene, floor, 128, 8)
        accuracy_costs_time(scene, floor, 32, [0.1], cap=10, reference_spp=1024)
        peak_memory(128, 4)
        speedup(scene, floor, 64, 8)
    else:
        throughput(scene, floor, 1024, 8)
        accuracy_costs_time(scene, floor, 64, [0.10, 0.05, 0.03], cap=60, reference_spp=4096)
        peak_memory(1024, 4)
        speedup(scene, floor, 512, 8)


if __name__ == "__main__":
    main()
