"""The built-in demo scene: a room with a table under a rectangular ceiling
light (the paper's dining-room case), a second, warm wall light and a cabinet
that shadows the floor. The floor carries the UV map that is baked.

Units are metres; light radiance in W/(m² sr).
"""
import math

import numpy as np


def box(center, size):
    """An axis-aligned box as (vertices (8,3), triangles (12,3)), outward winding."""
    c = np.asarray(center, float)
    h = np.asarray(size, float) / 2
    corners = np.array([[x, y, z] for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)], float)
    vertices = c + corners * h
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    triangles = [t for a, b, c_, d in quads for t in ((a, b, c_), (a, c_, d))]
    return vertices, np.array(triangles, np.uint32)


def grid(size_x, size_y, cells, z=0.0):
    """A floor grid centred on the origin facing +z, with per-corner UVs over [0,1]²."""
    xs = np.linspace(-size_x / 2, size_x / 2, cells + 1)
    ys = np.linspace(-size_y / 2, size_y / 2, cells + 1)
    gx, gy = np.meshgrid(xs, ys)
    vertices = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, z)], axis=1)
    idx = np.arange((cells + 1) ** 2).reshape(cells + 1, cells + 1)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]).astype(np.uint32)
    corner_positions = vertices[triangles.reshape(-1)]
    uvs = np.stack([(corner_positions[:, 0] + size_x / 2) / size_x,
                    (corner_positions[:, 1] + size_y / 2) / size_y], axis=1)
    return vertices, triangles, uvs


def build_scene(omis_module):
    """Builds and commits the demo scene; returns (scene, floor_mesh_id, description)."""
    scene = omis_module.Scene()
    floor_v, floor_t, floor_uv = grid(6.0, 6.0, 12)
    floor = scene.add_mesh(floor_v, floor_t, uvs=floor_uv)

    room_w, room_h = 6.0, 2.6
    for center, size in [((0, 3.05, room_h / 2), (6.2, 0.1, room_h)),    # walls
                         ((0, -3.05, room_h / 2), (6.2, 0.1, room_h)),
                         ((3.05, 0, room_h / 2), (0.1, 6.2, room_h)),
                         ((-3.05, 0, room_h / 2), (0.1, 6.2, room_h)),
                         ((0, 0, room_h + 0.05), (6.2, 6.2, 0.1)),       # ceiling
                         ((-0.6, -0.2, 0.74), (1.6, 0.9, 0.04)),         # table top
                         ((2.2, 1.3, 0.6), (0.5, 0.6, 1.2))]:            # cabinet
        v, t = box(center, size)
        scene.add_mesh(v, t)
    for lx in (-1.3, 0.1):                                                 # table legs
        for ly in (-0.6, 0.2):
            v, t = box((lx, ly, 0.36), (0.05, 0.05, 0.72))
            scene.add_mesh(v, t)

    # Ceiling light over the table, parallel to it (emits toward cross(u, v) = −z).
    scene.add_rect_light(corner=(-1.2, -0.5, 2.2), edge_u=(0, 0.6, 0), edge_v=(1.2, 0, 0),
                         radiance=(9.0, 9.0, 9.0))
    # Warm light on the +x wall facing −x, behind the cabinet.
    scene.add_rect_light(corner=(2.95, 1.0, 1.2), edge_u=(0, 0, 0.5), edge_v=(0, 0.8, 0),
                         radiance=(24.0, 18.0, 12.0))
    scene.commit()
    return scene, floor, "room 6×6 m: table under a ceiling light, a wall light and a cabinet"


def sky(width=1024, height=512, sun_elevation=30.0, sun_azimuth=0.0, sun_diameter=0.5,
        sun_radiance=3.0e5):
    """A procedural equirectangular HDR sky for image-world tests and benchmarks
    (nothing downloaded): a blue gradient above the horizon, a dim ground and a
    sun disc (texels whose centre lies inside it) toward (elevation, azimuth) in
    degrees. Returns (rgb (height, width, 3) float32, rows top first, in Cycles'
    convention u = 0.5 − atan2(y, x)/2π, v = 1 − acos(z)/π; the sun's unit direction)."""
    u = (np.arange(width) + 0.5) / width
    v = 1 - (np.arange(height) + 0.5) / height
    phi = math.pi * (1 - 2 * u)[None, :]
    theta = math.pi * (1 - v)[:, None]
    d = np.stack(np.broadcast_arrays(np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                                     np.cos(theta)), axis=-1)
    z = d[..., 2:3]
    rgb = np.where(z > 0, (1 - z) * np.array([0.6, 0.8, 1.0]) + z * np.array([0.2, 0.35, 0.8]),
                   np.array([0.08, 0.07, 0.06]))
    el, az = math.radians(sun_elevation), math.radians(sun_azimuth)
    sun = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    rgb[d @ sun >= math.cos(math.radians(sun_diameter / 2))] = sun_radiance * np.array(
        [1.0, 0.95, 0.9])
    return rgb.astype(np.float32), sun
