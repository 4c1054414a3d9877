"""Extreme and malformed input through the Python API (issue 11): clear errors
naming the argument the caller wrote, or the right answer — never NaN from
finite input, never an unstoppable call."""
import os
import threading
import time

import numpy as np
import pytest

import omis


def floor_scene():
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    t = np.array([[0, 1, 2], [0, 2, 3]], np.uint32)
    uv = (v[t.reshape(-1)][:, :2] + 1) / 2
    scene = omis.Scene()
    mesh = scene.add_mesh(v, t, uvs=uv)
    scene.add_rect_light((-0.5, -0.5, 1.0), (0, 1, 0), (1, 0, 0), radiance=2.0)
    scene.commit()
    return scene, mesh


P = np.array([[0.0, 0.0, 0.0]])
N = np.array([[0.0, 0.0, 1.0]])


@pytest.mark.parametrize("strategy", ["balance", "power", "maximum", "cutoff",
                                      "optimal-direct", "optimal-progressive"])
@pytest.mark.parametrize("pdf", [1.7e308, 1e-320])
def test_combine_with_extreme_pdfs_is_finite_or_refused(strategy, pdf):
    f = np.ones(8) * (pdf if pdf < 1 else 1.0)  # f/pdf stays representable
    pdfs = np.full((8, 2), pdf)
    technique = np.array([0, 0, 1, 1] * 2)
    estimate, variance = omis.combine(f, pdfs, technique, [2, 2], strategy=strategy,
                                      return_variance=True)
    assert np.all(np.isfinite(estimate)) and np.all(np.isfinite(variance))
    # Every sample's f/(Σ n p) is 1/4 of f/pdf: the estimate is f/pdf exactly.
    np.testing.assert_allclose(estimate, f[0] / pdf, rtol=1e-12)


def test_combine_refuses_values_whose_square_overflows():
    with pytest.raises(ValueError, match="f, pdfs"):
        omis.combine(np.ones(4), np.full((4, 2), 1e-320), np.array([0, 0, 1, 1]), [2, 2])


def test_combine_option_types_name_the_argument():
    args = (np.ones(4), np.ones((4, 2)), np.array([0, 0, 1, 1]), [2, 2])
    with pytest.raises(TypeError, match="beta"):
        omis.combine(*args, strategy="power", beta="2")
    with pytest.raises(TypeError, match="cutoff"):
        omis.combine(*args, strategy="cutoff", cutoff=[0.1])
    with pytest.raises(TypeError, match="return_variance"):
        omis.combine(*args, return_variance="yes")
    assert len(omis.combine(*args, return_variance=np.bool_(True))) == 2


def test_counts_that_overflow_are_refused():
    scene, _ = floor_scene()
    with pytest.raises(ValueError, match="samples"):
        omis.direct_lighting(scene, P, N, ["bsdf", "uniform/area"], [2**31 - 1] * 2)
    with pytest.raises(ValueError, match="counts"):
        omis.bake_uv(scene, 0, 4, 4, techniques=["bsdf", "uniform/area"],
                     counts=[2**31 - 1] * 2, samples=2**30)


def _cancel_after(seconds):
    start = time.monotonic()
    state = {}

    def progress(fraction):
        if time.monotonic() - start < seconds:
            return True
        state.setdefault("refused", time.monotonic())
        return False
    return progress, state


def test_huge_counts_are_cancelled_promptly():
    scene, mesh = floor_scene()
    progress, state = _cancel_after(0.2)
    with pytest.raises(omis.Cancelled):
        omis.direct_lighting(scene, P, N, ["bsdf", "uniform/area"], [2**29, 2**29],
                             progress=progress)
    # Not a speed target: without checks inside a point this ran for minutes.
    assert time.monotonic() - state["refused"] < 5
    progress, state = _cancel_after(0.2)
    with pytest.raises(omis.Cancelled):
        omis.bake_vertices(scene, mesh, techniques=["bsdf", "uniform/area"],
                           counts=[2**29, 2**29], samples=2**30, progress=progress)
    assert time.monotonic() - state["refused"] < 5


def test_bright_lights_are_refused_up_front():
    scene = omis.Scene()
    with pytest.raises(ValueError, match="radiance"):
        scene.set_world(1e308)
    with pytest.raises(ValueError, match="intensity"):
        scene.add_point_light((0, 0, 1), 1e308)


def test_lights_at_extreme_sizes_name_the_argument():
    scene = omis.Scene()
    with pytest.raises(ValueError, match=r"radius: 1e-160 m is too small"):
        scene.add_disk_light((0, 0, 1), (0, 0, -1), 1e-160, 1.0)
    with pytest.raises(ValueError, match="^radius: 1e[+]200 m: lies beyond"):
        scene.add_disk_light((0, 0, 1), (0, 0, -1), 1e200, 1.0)
    with pytest.raises(ValueError, match="points: point 1 "):
        floor, _ = floor_scene()
        omis.direct_lighting(floor, np.array([[0, 0, 0], [1e300, 0, 0.0]]), np.array([N[0]] * 2))
    # Below a micrometre a sphere light is a point (the right answer to 1e-6
    # relative from a millimetre on), never a light too narrow to sample.
    scene.add_point_light((0, 0, 1), 1.0, radius=1e-300)
    # Huge and tiny direction vectors are directions.
    scene.add_spot_light((0, 0, 1), (0, 0, -1e300), 1.0, spot_size=1.0)
    scene.add_sun_light((0, 0, -1e-300), 1.0, angle=1e-300)
    scene.add_disk_light((0, 0, 1), (0, 0, -1e300), 0.5, 1.0)


def test_bake_arguments_are_named():
    scene, mesh = floor_scene()
    with pytest.raises(ValueError, match="^counts: entry 0 is negative"):
        omis.bake_uv(scene, mesh, 4, 4, techniques=["bsdf", "uniform/area"], counts=[-1, 2])
    with pytest.raises(TypeError, match="time_budget"):
        omis.bake_uv(scene, mesh, 4, 4, time_budget="1")
    with pytest.raises(ValueError, match="^samples: .*less than one round"):
        omis.bake_uv(scene, mesh, 4, 4, techniques=["bsdf"], counts=[100], samples=1)
    calls = []
    started = time.monotonic()
    with pytest.raises(ValueError, match="progress"):
        omis.bake_uv(scene, mesh, 256, 256, samples=4096, progress=5)
    assert time.monotonic() - started < 1  # refused before baking, not after


def test_paths_and_exposure(tmp_path):
    scene, mesh = floor_scene()
    result = omis.bake_uv(scene, mesh, 4, 4, samples=4)
    for write in (result.write_exr, result.write_png):
        with pytest.raises(ValueError, match="path"):
            write(str(tmp_path / "a\x00.img"))
    for exposure in (float("nan"), float("inf")):
        with pytest.raises(ValueError, match="exposure"):
            result.write_png(str(tmp_path / "b.png"), exposure=exposure)
    assert os.listdir(tmp_path) == []
