"""Scene snapshots (Scene.save / Scene.load / to_bytes / from_bytes).

A loaded scene bakes the same bits as the scene saved, for every kind of light,
receiver, flag and option; damaged files (truncated, flipped bytes, another
version, counts larger than the file, sections unknown or missing) raise
ValueError naming the problem, never crash or hang.
"""
import random
import struct
import zlib

import numpy as np
import pytest

import omis
from omis import demo


def sphere(center, radius, rings=6, segments=12):
    """A UV sphere (2·segments·(rings − 1) triangles), outward winding."""
    verts = [(0, 0, 1)]
    for r in range(1, rings):
        th = np.pi * r / rings
        for s in range(segments):
            ph = 2 * np.pi * s / segments
            verts.append((np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)))
    verts.append((0, 0, -1))
    tris = []
    ring = lambda r, s: 1 + (r - 1) * segments + s % segments
    for s in range(segments):
        tris.append((0, ring(1, s), ring(1, s + 1)))
        tris.append((len(verts) - 1, ring(rings - 1, s + 1), ring(rings - 1, s)))
    for r in range(1, rings - 1):
        for s in range(segments):
            a, b, c, d = ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r, s + 1)
            tris += [(a, b, c), (a, c, d)]
    return np.asarray(center) + radius * np.array(verts), np.array(tris, np.uint32)


def every_feature_scene(mesh_lights=True):
    """Every light kind, flags, receivers, names, normals and an emissive mesh."""
    scene = omis.Scene()
    v, t, uv = demo.grid(4.0, 4.0, 4)
    normals = np.tile([0.0, 0.1, 1.0], (3 * len(t), 1))
    floor = scene.add_mesh(v, t, normals=normals, uvs=uv)
    scene.set_mesh_name(floor, "floor")
    scene.set_receiver(floor, "principled", 0.4)
    bv, bt = demo.box((0.8, 0.3, 0.4), (0.5, 0.5, 0.8))
    box = scene.add_mesh(bv.astype(np.float32), bt)
    scene.set_mesh_name(box, "crate")
    sv, st = sphere((-1.0, 0.8, 0.7), 0.3)
    scene.add_mesh(sv, st, emission=(2.0, 1.5, 1.0))
    scene.add_rect_light((-0.5, -0.5, 2.0), (0, 1, 0), (1, 0, 0), radiance=(4, 4, 4), spread=1.2)
    scene.add_ellipse_light((1.5, -1.0, 1.5), (0.2, 0, 0), (0, 0.1, 0), radiance=3.0,
                            two_sided=True)
    disk = scene.add_disk_light((-1.5, -1.5, 1.0), (1, 1, -1), 0.2, radiance=5.0)
    scene.set_light_flags(disk, cast_shadow=False, visible_to_bsdf=False)
    scene.add_point_light((0.5, 1.5, 1.2), intensity=(3, 2, 1))
    scene.add_point_light((-0.5, 1.0, 1.0), intensity=2.0, radius=0.1)
    scene.add_spot_light((1.0, 1.0, 2.0), (0, 0, -1), intensity=20.0, spot_size=0.9,
                         spot_blend=0.3, radius=0.05)
    scene.add_sun_light((0.3, 0.2, -1), irradiance=(0.5, 0.5, 0.4), angle=0.05)
    scene.set_world((0.05, 0.06, 0.08))
    scene.set_mesh_lights(mesh_lights)
    scene.commit()
    return scene, floor


def bake_bits(scene, mesh):
    r = omis.bake_uv(scene, mesh, 24, 20, samples=8, seed=11, margin=3)
    return r.value.tobytes() + r.noise.tobytes() + r.mask.tobytes()


@pytest.mark.parametrize("mesh_lights", [True, False])
def test_round_trip_bakes_the_same_bits(tmp_path, mesh_lights):
    scene, floor = every_feature_scene(mesh_lights)
    path = str(tmp_path / "level.omis")
    scene.save(path)
    loaded = omis.Scene.load(path)
    assert loaded.num_meshes == 3
    assert loaded.find_mesh("crate") == 1 and loaded.mesh_name(0) == "floor"
    assert bake_bits(loaded, floor) == bake_bits(scene, floor)
    vertex_bits = lambda s: omis.bake_vertices(s, 1, samples=4, seed=2).value.tobytes()
    assert vertex_bits(loaded) == vertex_bits(scene)
    # Saving the loaded scene gives the same file: nothing lost, nothing added.
    assert loaded.to_bytes() == scene.to_bytes()


def test_uncommitted_scene_saves_too():
    scene = omis.Scene()
    v, t, uv = demo.grid(2.0, 2.0, 2)
    scene.add_mesh(v, t, uvs=uv)
    scene.add_point_light((0, 0, 1), intensity=1.0)
    loaded = omis.Scene.from_bytes(scene.to_bytes())
    scene.commit()
    assert bake_bits(loaded, 0) == bake_bits(scene, 0)


def image_world_scene(compensate):
    """A floor and a box under an image world (a sky gradient with a bright sun
    texel), rotated, with the world's flags changed."""
    scene = omis.Scene()
    v, t, uv = demo.grid(2.0, 2.0, 2)
    floor = scene.add_mesh(v, t, uvs=uv)
    bv, bt = demo.box((0.4, 0.4, 0.4), (0.2, 0.1, 0.2))
    scene.add_mesh(bv, bt)
    sky = np.empty((16, 32, 3), np.float32)
    sky[...] = np.linspace(1.0, 0.2, 16, dtype=np.float32)[:, None, None]
    sky[3, 7] = (400.0, 380.0, 300.0)
    world = scene.set_world_image(sky, rotation=(0.1, -0.2, 0.7), compensate=compensate)
    scene.set_light_flags(world, cast_shadow=True, visible_to_bsdf=True)
    scene.add_point_light((0.5, 0.5, 1.0), intensity=1.0)
    scene.commit()
    return scene, floor


@pytest.mark.parametrize("compensate", [False, True])
def test_image_world_round_trip(compensate):
    scene, floor = image_world_scene(compensate)
    data = scene.to_bytes()
    assert [s[0] for s in sections(data)][-1] == b"WMAP"
    loaded = omis.Scene.from_bytes(data)
    assert bake_bits(loaded, floor) == bake_bits(scene, floor)
    assert loaded.to_bytes() == data


def test_image_world_map_damage_is_caught():
    scene, _ = image_world_scene(False)
    parts = sections(scene.to_bytes())
    wmap = parts[-1]
    # A texel made NaN (the map's own validation names it) and a size larger
    # than the texels stored (refused before allocating).
    bad = bytearray(wmap[2])
    bad[12 + 24:12 + 28] = struct.pack("<f", float("nan"))
    refused(assemble(parts[:-1] + [[wmap[0], wmap[1], bytes(bad)]]))
    huge = bytearray(wmap[2])
    huge[0:8] = struct.pack("<II", 60000, 60000)
    refused(assemble(parts[:-1] + [[wmap[0], wmap[1], bytes(huge)]]), "does not fit")
    # Beside lights that hold no world for it.
    plain = omis.Scene()
    v, t, uv = demo.grid(2.0, 2.0, 2)
    plain.add_mesh(v, t, uvs=uv)
    plain.add_point_light((0, 0, 1), intensity=1.0)
    refused(assemble(sections(plain.to_bytes()) + [wmap]), "no world light")


# ---- Damaged files -------------------------------------------------------------

def sections(data):
    """The file's sections as [tag, flags, payload] (the layout of scene_snapshot.h)."""
    count = struct.unpack_from("<I", data, 12)[0]
    out = []
    for k in range(count):
        tag, flags, offset, size, crc, _ = struct.unpack_from("<4sIQQII", data, 16 + 32 * k)
        assert zlib.crc32(data[offset:offset + size]) == crc
        out.append([tag, flags, bytes(data[offset:offset + size])])
    return out


def assemble(parts, version=1):
    """A file of these sections, with correct checksums."""
    header = b"OMISSNAP" + struct.pack("<II", version, len(parts))
    offset = len(header) + 32 * len(parts) + 4
    table = b""
    for tag, flags, payload in parts:
        table += struct.pack("<4sIQQII", tag, flags, offset, len(payload),
                             zlib.crc32(payload), 0)
        offset += len(payload)
    head = header + table
    return head + struct.pack("<I", zlib.crc32(head)) + b"".join(p for _, _, p in parts)


@pytest.fixture(scope="module")
def snapshot():
    scene, _ = every_feature_scene()
    return scene.to_bytes()


def refused(data, *words):
    with pytest.raises(ValueError) as error:
        omis.Scene.from_bytes(bytes(data))
    for word in words:
        assert word in str(error.value)


def test_the_file_is_as_documented(snapshot):
    assert assemble(sections(snapshot)) == snapshot
    assert [s[0] for s in sections(snapshot)] == [b"OPTS", b"GEOM", b"RECV", b"LITE"]


def test_truncated_files(snapshot):
    rng = random.Random(5)
    lengths = list(range(0, 80)) + rng.sample(range(80, len(snapshot)), 150)
    for n in lengths:
        refused(snapshot[:n])
    refused(snapshot[:10], "truncated")
    refused(snapshot[:len(snapshot) - 1], "truncated")


def test_every_flipped_byte_is_caught(snapshot):
    # Every byte lies under a checksum (header and table, or its section's), or
    # is the magic, the version or a checksum itself.
    rng = random.Random(9)
    for position in list(range(0, 160)) + rng.sample(range(160, len(snapshot)), 300):
        data = bytearray(snapshot)
        data[position] ^= 1 << rng.randrange(8)
        refused(data)
    data = bytearray(snapshot)
    data[-3] ^= 0x40
    refused(data, "LITE", "checksum")


def test_wrong_version_and_magic(snapshot):
    refused(assemble(sections(snapshot), version=2), "version 2")
    refused(b"PNG\0" + snapshot[4:], "magic")


def test_huge_counts_are_refused_before_allocating(snapshot):
    parts = sections(snapshot)
    geom = parts[1][2]
    name_length = struct.unpack_from("<I", geom, 4)[0]
    at = 8 + name_length  # the first mesh's vertex count
    for count in (2**62, 2**40, 10**9):
        parts[1][2] = geom[:at] + struct.pack("<Q", count) + geom[at + 8:]
        refused(assemble(parts), "GEOM", "does not fit")
    parts[1][2] = struct.pack("<I", 0xFFFFFFFF) + geom[4:]  # mesh count
    refused(assemble(parts), "does not fit")
    lights = sections(snapshot)
    lights[3][2] = struct.pack("<I", 0x7FFFFFFF) + lights[3][2][4:]
    refused(assemble(lights), "LITE", "does not fit")
    header = bytearray(snapshot)
    header[12:16] = struct.pack("<I", 0xFFFFFFFF)  # section count
    refused(header, "sections")


def test_sections_unknown_missing_or_repeated(snapshot):
    parts = sections(snapshot)
    extra = [b"XTRA", 0, b"a section of a later omis that bakes may ignore"]
    loaded = omis.Scene.from_bytes(assemble(parts + [extra]))
    assert loaded.num_meshes == 3
    refused(assemble(parts + [[b"XTRA", 1, b"needed"]]), "XTRA", "required")
    refused(assemble(parts[:2] + parts[3:]), "RECV", "missing")
    refused(assemble(parts + [parts[0]]), "OPTS", "twice")


def test_bad_values_inside_sound_files(snapshot):
    parts = sections(snapshot)
    lite = bytearray(parts[3][2])
    lite[4:8] = struct.pack("<I", 7)  # the first light's type: Mesh, made by commit only
    parts[3][2] = bytes(lite)
    refused(assemble(parts), "unknown type")
    parts = sections(snapshot)
    lite = bytearray(parts[3][2])
    lite[16:24] = struct.pack("<d", float("nan"))  # its emission
    parts[3][2] = bytes(lite)
    refused(assemble(parts), "not finite")


def test_missing_file(tmp_path):
    with pytest.raises(RuntimeError, match="cannot open"):
        omis.Scene.load(str(tmp_path / "absent.omis"))
