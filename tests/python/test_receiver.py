"""scene.set_receiver: bad input names its argument; bakes under a delta sun follow
Cycles 3.4's closures viewed along the normal (exact values, formulas written here)."""
import math

import numpy as np
import pytest

import omis

QUAD = (np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32),
        np.array([[0, 1, 2], [0, 2, 3]], np.int32))


def sun_scene(theta, receivers):
    scene = omis.Scene()
    ids = []
    for model, roughness in receivers:
        mesh = scene.add_mesh(*QUAD)
        if model is not None:
            scene.set_receiver(mesh, model, roughness=roughness)
        ids.append(mesh)
    scene.add_sun_light((-math.sin(theta), 0, -math.cos(theta)), irradiance=1.0)
    scene.commit()
    return scene, ids


def test_bad_input():
    scene = omis.Scene()
    mesh = scene.add_mesh(*QUAD)
    with pytest.raises(ValueError, match="model"):
        scene.set_receiver(mesh, "velvet")
    with pytest.raises(ValueError, match="roughness"):
        scene.set_receiver(mesh, "principled", roughness=float("nan"))
    with pytest.raises(ValueError, match="mesh"):
        scene.set_receiver(5, "principled", roughness=0.5)
    scene.commit()
    with pytest.raises(RuntimeError, match="committed"):
        scene.set_receiver(mesh, "lambert")


@pytest.mark.parametrize("degrees", [60.0, 79.0])
def test_closures_under_a_grazing_sun(degrees):
    theta = math.radians(degrees)
    c = math.cos(theta)
    f = (1 - c) ** 5
    cases = [(None, 0.0, 1.0), ("lambert", 0.3, 1.0)]
    cases += [("principled", r, 1 - 0.5 * f + r * (1 + c) * f) for r in (0.0, 0.5, 1.0)]
    cases += [("oren-nayar", s, math.pi / (math.pi + (3 * math.pi - 4) / 6 * s))
              for s in (0.0, 0.5, 1.0)]
    scene, ids = sun_scene(theta, [(m, r) for m, r, _ in cases])
    for mesh, (model, roughness, ratio) in zip(ids, cases):
        result = omis.bake_vertices(scene, mesh, techniques=["bsdf"], counts=[1], samples=1)
        np.testing.assert_allclose(result.value[:, 0], c / math.pi * ratio, rtol=1e-6,
                                   err_msg=f"{model} {roughness}")
