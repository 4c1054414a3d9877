"""Scene.set_world_image (SPEC §4, §6): an equirectangular world from an array or a file.

Exact answers are written here from Cycles' convention (u = 0.5 - atan2(y, x)/2π,
v = 1 - acos(z)/π, rows top first): a constant map and one bright texel. Estimates
are means over independent copies of one point; they must lie within 4 standard
errors measured from the copies' spread (seeds fixed, so runs are reproducible).
"""
import math
import shutil
import struct
import subprocess

import numpy as np
import pytest

import omis

K_SIGMA = 4.0
COPIES = 64


def copies_mean(scene, normal, techniques, samples, strategy, seed):
    points = np.zeros((COPIES, 3))
    normals = np.tile(np.asarray(normal, float), (COPIES, 1))
    value, _ = omis.direct_lighting(scene, points, normals, techniques, samples,
                                    strategy=strategy, seed=seed)
    green = value[:, 1]
    return green.mean(), green.std(ddof=1) / math.sqrt(COPIES)


def world_scene(image, **kwargs):
    scene = omis.Scene()
    scene.set_world_image(image, **kwargs)
    scene.commit()
    return scene


def write_hdr(path, rgb):
    """A flat (uncompressed) Radiance RGBE file, rows top first."""
    h, w, _ = rgb.shape
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w))
    for r, g, b in rgb.reshape(-1, 3).astype(float):
        m = max(r, g, b)
        if m < 1e-32:
            out += bytes(4)
            continue
        mant, e = math.frexp(m)
        scale = mant * 256.0 / m
        out += struct.pack("BBBB", int(r * scale), int(g * scale), int(b * scale), e + 128)
    path.write_bytes(bytes(out))


def one_texel_map(w=8, h=4, column=5, row=1, radiance=500.0):
    rgb = np.zeros((h, w, 3), np.float32)
    rgb[row, column] = radiance
    return rgb


def one_texel_exact(w=8, h=4, row=1, radiance=500.0):
    """E/π at an up-facing point: (L/π)(2π/w)(sin²θ1 - sin²θ0)/2."""
    t0, t1 = math.pi * row / h, math.pi * (row + 1) / h
    return radiance / math.pi * (2 * math.pi / w) * (math.sin(t1) ** 2 - math.sin(t0) ** 2) / 2


@pytest.mark.parametrize("strategy", ["balance", "optimal-direct"])
def test_constant_map_is_the_constant_world(strategy):
    c = np.array([0.75, 1.5, 0.25], np.float32)
    scene = world_scene(np.tile(c, (16, 32, 1)), rotation=(0.1, 0.2, 0.3))
    mean, se = copies_mean(scene, (0.2, 0.1, 1), ["uniform/solid-angle", "bsdf"], [8, 8],
                           strategy, 3)
    assert abs(mean - 1.5) <= K_SIGMA * se + 1e-9


@pytest.mark.parametrize("compensate", [False, True])
def test_one_bright_texel_against_its_closed_form(compensate):
    # A coarse map: cosine draws meet the texel 1/16 of the time, so the copies'
    # spread resolves their share of the combined estimate (test_environment_map.cpp).
    scene = world_scene(one_texel_map(), compensate=compensate)
    exact = one_texel_exact()
    for strategy in ("balance", "optimal-direct"):
        mean, se = copies_mean(scene, (0, 0, 1), ["uniform/solid-angle", "bsdf"], [16, 16],
                               strategy, 5)
        assert abs(mean - exact) <= K_SIGMA * se + 1e-9 * exact, (strategy, mean, se, exact)


def test_rotation_moves_the_texel():
    # Rz(90°) looks up the texel of R·ω: the texel first seen around +X·cos + ... is
    # now seen from the direction turned by -90° about z; a receiver facing that
    # direction gets what a receiver facing the texel got before.
    rgb = one_texel_map()
    plain = world_scene(rgb)
    turned = world_scene(rgb, rotation=(0.0, 0.0, math.pi / 2))
    # The texel's centre direction (u = 0.6875, v = 1 - 0.375).
    u, v = (5 + 0.5) / 8, 1 - (1 + 0.5) / 4
    phi, theta = math.pi * (1 - 2 * u), math.pi * (1 - v)
    d = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi),
                  math.cos(theta)])
    d_turned = np.array([d[1], -d[0], d[2]])  # Rz(-90°)·d
    a, se_a = copies_mean(plain, d, ["uniform/solid-angle", "bsdf"], [16, 16], "balance", 7)
    b, se_b = copies_mean(turned, d_turned, ["uniform/solid-angle", "bsdf"], [16, 16],
                          "balance", 8)
    assert a > 0.5
    assert abs(a - b) <= K_SIGMA * math.hypot(se_a, se_b)


def test_hdr_and_exr_files(tmp_path):
    rgb = one_texel_map(radiance=512.0)  # exact in RGBE
    hdr = tmp_path / "sky.hdr"
    write_hdr(hdr, rgb)
    exact = one_texel_exact(radiance=512.0)
    files = [hdr, str(hdr)]
    if shutil.which("oiiotool"):
        exr = tmp_path / "sky.exr"
        subprocess.run(["oiiotool", str(hdr), "-d", "float", "-o", str(exr)], check=True)
        files.append(exr)
    for path in files:
        scene = world_scene(path)
        mean, se = copies_mean(scene, (0, 0, 1), ["uniform/solid-angle", "bsdf"], [16, 16],
                               "balance", 9)
        assert abs(mean - exact) <= K_SIGMA * se + 1e-9 * exact, (path, mean, se, exact)


def bad_texel(value):
    rgb = np.ones((4, 8, 3), np.float32)
    rgb[2, 3, 1] = value
    return rgb


@pytest.mark.parametrize("image, kwargs, words", [
    (bad_texel(np.nan), {}, ["row 2, column 3, channel 1", "NaN"]),
    (bad_texel(-1.0), {}, ["negative"]),
    (bad_texel(np.inf), {}, ["infinite"]),
    (np.ones((4, 8, 4), np.float32), {}, ["image", "(H, W, 3)"]),
    (np.ones((4, 8), np.float32), {}, ["image", "(H, W, 3)"]),
    (np.ones((0, 8, 3), np.float32), {}, ["image", "(H, W, 3)"]),
    (np.ones((4, 8, 3), np.int32), {}, ["image", "float"]),
    (np.ones((4, 8, 3), np.float32), {"rotation": (0, math.nan, 0)}, ["rotation"]),
    (np.ones((4, 8, 3), np.float32), {"rotation": (0, 1)}, ["rotation"]),
    ("/nonexistent/sky.exr", {}, ["/nonexistent/sky.exr"]),
])
def test_bad_world_images_are_refused(image, kwargs, words):
    scene = omis.Scene()
    with pytest.raises(ValueError) as err:
        scene.set_world_image(image, **kwargs)
    for word in words:
        assert word in str(err.value)


def test_compensation_without_bsdf_is_refused():
    scene = world_scene(one_texel_map(), compensate=True)
    with pytest.raises(ValueError, match="MIS compensation"):
        omis.direct_lighting(scene, np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]),
                             ["uniform/solid-angle"], [4])
