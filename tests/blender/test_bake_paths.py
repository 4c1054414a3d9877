"""Error and cancel paths leave images and attributes untouched; the write-back modes
(float / 8-bit sRGB images, clear, margin, color attributes POINT and CORNER); the
operator's arguments; the worker-thread path the modal operator uses.

    scripts/blender_run.sh tests/blender/test_bake_paths.py
"""

import math
import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

import omis_bake  # noqa: E402
from omis_bake import native, writeback  # noqa: E402
from omis_bake.job import BakeJob  # noqa: E402
from omis_bake.settings import settings_from  # noqa: E402

check = U.check
MARK = (0.25, 0.5, 0.75, 0.5)


def setup(res=16, light=True, n_objects=1, float_buffer=True):
    U.reset_scene()
    objects, images = [], []
    for i in range(n_objects):
        img = U.make_image(f"img{i}", res, float_buffer=float_buffer)
        U.set_pixels(img, MARK)
        ob = U.grid_mesh(f"Plane{i}", size=1.0, cuts=1, location=(1.2 * i, 0, 0))
        ob.data.materials.append(U.image_material(f"mat{i}", img))
        objects.append(ob)
        images.append(img)
    if light:
        U.add_light('AREA', "lamp", energy=300.0, location=(0.3, 0.2, 1.5), size=0.5)
    U.select_only(objects)
    return objects, images


def untouched(images):
    for img in images:
        px = U.pixels(img)
        check(np.allclose(px, np.asarray(MARK, np.float32), atol=1e-6),
              f'image "{img.name}" was changed')


def expect_error(text, images, **settings):
    try:
        omis_bake.bake(bpy.context, **settings)
    except omis_bake.BakeError as exc:
        check(text in str(exc), f"expected {text!r} in the error, got {exc}")
    else:
        raise AssertionError(f"no error (expected {text!r})")
    untouched(images)
    try:
        bpy.ops.omis.bake(**settings)
    except RuntimeError as exc:  # the operator's ERROR report
        check(text in str(exc), f"operator: expected {text!r}, got {exc}")
    else:
        raise AssertionError(f"operator reported no error (expected {text!r})")
    untouched(images)


def test_errors_leave_images_untouched():
    objects, images = setup()
    U.select_only([])
    expect_error("nothing selected", images)

    objects, images = setup()
    U.select_only(objects + [bpy.data.objects["lamp"]])
    expect_error("is not a mesh", images)

    objects, images = setup()
    objects[0].data.uv_layers.remove(objects[0].data.uv_layers[0])
    expect_error("has no UV map", images)

    objects, images = setup()
    mat = objects[0].data.materials[0]
    for node in list(mat.node_tree.nodes):
        if node.type == 'TEX_IMAGE':
            mat.node_tree.nodes.remove(node)
    expect_error("no active Image Texture node", images)

    objects, images = setup()
    objects[0].data.materials.clear()
    expect_error("has no material", images)

    objects, images = setup()
    objects[0].hide_render = True
    expect_error("not enabled for rendering", images)

    objects, images = setup()
    expect_error("has no color attribute", images, target='COLOR_ATTRIBUTES')


def test_no_lights_is_black_with_warning():
    objects, images = setup(light=False)
    stats = omis_bake.bake(bpy.context, samples=4, margin=0)
    check(any("no lights" in w for w in stats["warnings"]), f"warnings {stats['warnings']}")
    px = U.pixels(images[0])
    check(np.all(px[..., :3] == 0) and np.all(px[..., 3] == 1), "not a black, baked result")


def test_cancel_and_failure_leave_images_untouched():
    objects, images = setup(res=64, n_objects=2)
    calls = []

    def stop(fraction):
        calls.append(fraction)
        return len(calls) < 2

    try:
        omis_bake.bake(bpy.context, samples=200000, progress=stop)
    except omis_bake.Cancelled:
        pass
    else:
        raise AssertionError("progress returning False did not cancel")
    untouched(images)

    # The second object fails after the first baked: nothing is written at all.
    omis = native.omis
    real = omis.bake_uv
    count = [0]

    def failing(*args, **kwargs):
        count[0] += 1
        if count[0] == 2:
            raise RuntimeError("simulated failure of the second object")
        return real(*args, **kwargs)

    omis.bake_uv = failing
    try:
        try:
            omis_bake.bake(bpy.context, samples=4)
        except omis_bake.BakeError as exc:
            check("simulated failure" in str(exc) and "no image" in str(exc), str(exc))
        else:
            raise AssertionError("the failure was not reported")
    finally:
        omis.bake_uv = real
    check(count[0] == 2, "the first object was not baked before the failure")
    untouched(images)


def test_worker_thread_and_cancel():
    objects, images = setup(res=32, n_objects=2)
    settings = settings_from(bpy.context.scene.omis, {"samples": 16, "seed": 3, "margin": 0})
    job = BakeJob(bpy.context, None, settings)
    job.start_thread()
    seen = []
    while not job.done:              # what the modal operator's timer does
        seen.append(job.fraction)
        time.sleep(0.01)
    threaded = job.finish(bpy.context)
    a = [U.pixels(img).copy() for img in images]
    check(seen == sorted(seen), "progress went backwards")
    for img in images:
        U.set_pixels(img, MARK)
    job = BakeJob(bpy.context, None, settings)
    job.run()
    job.finish(bpy.context)
    for before, img in zip(a, images):
        check(np.array_equal(before, U.pixels(img)), "threaded and synchronous bakes differ")
    check(threaded["covered"] > 0 and threaded["status"] == "complete", threaded["status"])

    for img in images:
        U.set_pixels(img, MARK)
    job = BakeJob(bpy.context, None, settings_from(bpy.context.scene.omis,
                                                   {"samples": 200000}))
    job.start_thread()
    time.sleep(0.3)
    job.cancel()                     # Esc
    job.thread.join(30)
    check(job.done and job.cancelled, "cancel did not stop the worker")
    try:
        job.finish(bpy.context)
    except omis_bake.Cancelled:
        pass
    else:
        raise AssertionError("finish after cancel wrote results")
    untouched(images)


def analytic_plane(res, light_pos, energy):
    u = (np.arange(res) + 0.5) / res
    uu, vv = np.meshgrid(u, u)
    p = np.stack([uu - 0.5, vv - 0.5, np.zeros_like(uu)], -1)
    w = np.asarray(light_pos) - p
    d2 = (w * w).sum(-1)
    return energy / (4 * math.pi) * (w[..., 2] / np.sqrt(d2)) / d2 / math.pi


def test_image_modes_clear_margin_srgb():
    # Float image, island in the middle of the UV square, margin 2, clear off.
    U.reset_scene()
    res = 32
    img = U.make_image("island", res)
    U.set_pixels(img, MARK)
    ob = U.grid_mesh("Island", size=1.0, cuts=1, uv_rect=(0.25, 0.25, 0.75, 0.75))
    ob.data.materials.append(U.image_material("m", img))
    U.add_light('SUN', "sun", energy=2.0, angle=0.0)
    U.select_only([ob])
    omis_bake.bake(bpy.context, samples=1, margin=2, use_clear=False)
    px = U.pixels(img)
    inside = px[8:24, 8:24]
    check(np.allclose(inside[..., :3], 2.0 / math.pi, rtol=1e-5), "island value")
    ring = px[6:26, 6:26].copy()
    ring[2:18, 2:18] = 0
    band = np.zeros((20, 20), bool)
    band[:, :] = True
    band[2:18, 2:18] = False
    check(np.allclose(ring[band][:, :3], 2.0 / math.pi, rtol=1e-5), "margin not filled")
    outer = np.ones((res, res), bool)
    outer[6:26, 6:26] = False
    check(np.allclose(px[outer], np.asarray(MARK, np.float32)), "clear=False changed outside")
    omis_bake.bake(bpy.context, samples=1, margin=0, use_clear=True)
    px = U.pixels(img)
    check(np.all(px[outer] == np.array([0, 0, 0, 0], np.float32)), "clear: not RGBA 0")

    # 8-bit sRGB image: Cycles writes the sRGB encoding of the linear value.
    img8 = U.make_image("byte", res, float_buffer=False)
    ob.data.materials[0].node_tree.nodes.active.image = img8
    bpy.data.lights["sun"].energy = 0.5 * math.pi       # E/π = 0.5 linear
    omis_bake.bake(bpy.context, samples=1, margin=0)
    px = U.pixels(img8)
    want = float(writeback.linear_to_srgb(np.array(0.5)))  # 0.7354
    check(abs(float(px[16, 16, 0]) - want) < 1.5 / 255, f"sRGB: {px[16, 16, 0]} vs {want}")


def test_color_attributes_and_operator_arguments():
    U.reset_scene()
    ob = U.grid_mesh("Colors", size=1.0, cuts=3)
    me = ob.data
    light_pos = (0.2, 0.1, 0.8)
    U.add_light('POINT', "lamp", energy=200.0, location=light_pos, shadow_soft_size=0.0)
    U.select_only([ob])
    co = np.array([v.co for v in me.vertices])
    w = np.asarray(light_pos) - co
    d2 = (w * w).sum(1)
    want_vertex = 200.0 / (4 * math.pi) * (w[:, 2] / np.sqrt(d2)) / d2 / math.pi
    for domain in ('POINT', 'CORNER'):
        attr = me.color_attributes.new(f"bake_{domain}", 'FLOAT_COLOR', domain)
        me.color_attributes.active_color = attr
        scene_samples = bpy.context.scene.omis.samples
        result = bpy.ops.omis.bake(target='COLOR_ATTRIBUTES', samples=1)
        check(result == {'FINISHED'}, f"operator {result}")
        check(bpy.context.scene.omis.samples == scene_samples,
              "operator arguments must not change the scene settings")
        n = len(attr.data)
        got = np.empty(n * 4, np.float32)
        attr.data.foreach_get("color", got)
        got = got.reshape(n, 4)
        if domain == 'POINT':
            want = want_vertex
        else:
            lv = np.empty(len(me.loops), np.int32)
            me.loops.foreach_get("vertex_index", lv)
            want = want_vertex[lv]
        # Corners are shaded 1e-4 m inside their face, as Cycles places them
        # (core/bake/vertex_points.h): E/d² at d ≈ 0.8 m moves by up to ~4e-4
        # relative there; the write-back itself is exact.
        check(np.allclose(got[:, 0], want, rtol=1e-3), f"{domain}: {got[:4, 0]} vs {want[:4]}")
        check(np.all(got[:, 3] == 1.0), "alpha")

    # Topology-changing modifiers cannot map back to the attribute.
    ob.modifiers.new("Subdivision", 'SUBSURF')
    try:
        omis_bake.bake(bpy.context, target='COLOR_ATTRIBUTES', samples=1)
    except omis_bake.BakeError as exc:
        check("change its topology" in str(exc), str(exc))
    else:
        raise AssertionError("topology change not reported")


def test_time_budget_and_noise_target():
    objects, images = setup(res=32, n_objects=2)
    stats = omis_bake.bake(bpy.context, samples=10 ** 7, time_budget=0.6)
    check(stats["status"] == "time budget reached", stats["status"])
    check(stats["seconds"] < 3.0, f"time budget 0.6 s took {stats['seconds']:.2f} s")
    stats = omis_bake.bake(bpy.context, samples=10 ** 7, use_noise_target=True,
                           noise_target=0.05)
    check(stats["status"] == "noise target reached", stats["status"])
    check(stats["mean_relative_error"] <= 0.05, f"mean error {stats['mean_relative_error']}")
    stats = omis_bake.bake(bpy.context, samples=64, use_optimal_mis=False, heuristic='POWER',
                           techniques=['bsdf', 'unoccluded/solid-angle'])
    check(stats["strategy"] == "power" and stats["techniques"] == ["bsdf",
                                                                   "unoccluded/solid-angle"],
          f"{stats['strategy']} {stats['techniques']}")
    check("bsdf" in stats["plan"], stats["plan"])


def test_shared_image_shares_time_by_texels():
    # Two objects baked into one image, one covering a fifth of it and one the
    # rest: a time limit is shared out by the texels each covers (1 : 4), so
    # both end with about the same samples per texel.
    U.reset_scene()
    img = U.make_image("atlas", 32)
    mat = U.image_material("atlas_mat", img)
    small = U.grid_mesh("Small", size=1.0, location=(0, 0, 0), uv_rect=(0.0, 0.0, 0.2, 1.0))
    large = U.grid_mesh("Large", size=1.0, location=(1.2, 0, 0), uv_rect=(0.2, 0.0, 1.0, 1.0))
    for ob in (small, large):
        ob.data.materials.append(mat)
    U.add_light('AREA', "lamp", energy=300.0, location=(0.6, 0.2, 1.5), size=0.5)
    U.select_only([small, large])
    job = BakeJob(bpy.context, [small, large],
                  settings_from(bpy.context.scene.omis, {"time_budget": 0.2}))
    weight = {u.part.object_name: u.weight for u in job.units}
    # UVs are float32 (0.2 is stored as 0.2000000030): relative 1e-6.
    check(abs(weight["Small"] / (0.2 * 32 * 32) - 1) < 1e-6
          and abs(weight["Large"] / (0.8 * 32 * 32) - 1) < 1e-6, f"unit weights {weight}")


def main():
    for test in (test_errors_leave_images_untouched, test_no_lights_is_black_with_warning,
                 test_cancel_and_failure_leave_images_untouched, test_worker_thread_and_cancel,
                 test_image_modes_clear_margin_srgb, test_time_budget_and_noise_target,
                 test_color_attributes_and_operator_arguments,
                 test_shared_image_shares_time_by_texels):
        start = time.perf_counter()
        test()
        print(f"ok {test.__name__} ({time.perf_counter() - start:.2f} s)")


main()
