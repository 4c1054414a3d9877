"""Results -> Blender images and color attributes, as Cycles writes them.

``compose_image`` and ``corner_to_loops`` are plain numpy; ``prepare_*`` read
the current pixels/colors (main thread) and return writer callables, so every
target is computed and checked before the first one is written.
"""

import numpy as np


def zeros(shape, dtype):
    """np.zeros on memory numpy has used before: np.zeros takes fresh pages
    (calloc), each faulting on its first write — ~110 faults a 128² bake,
    0.5–5 ms on the shared virtual machine, a small bake's share."""
    out = np.empty(shape, dtype)
    out.fill(0)
    return out


def ring_distance(mask, margin):
    """Chebyshev distance (in texels) to the nearest texel with mask > 0, capped:
    0 on the mask, k for the k-th ring of 8-neighbour dilation (k ≤ margin),
    margin + 1 beyond. The same rings the omis core fills its margin with."""
    covered = mask > 0
    dist = np.where(covered, 0, margin + 1).astype(np.int32)
    grown = covered.copy()
    for ring in range(1, margin + 1):
        g = grown.copy()
        g[1:, :] |= grown[:-1, :]
        g[:-1, :] |= grown[1:, :]
        h = g.copy()
        h[:, 1:] |= g[:, :-1]
        h[:, :-1] |= g[:, 1:]
        new = h & ~grown
        if not new.any():
            break
        dist[new] = ring
        grown = h
    return dist


def compose_image(parts, height, width, margin):
    """Composites per-part bakes of one image.

    parts: list of (value (H, W, 3), mask (H, W)) baked with the given margin.
    Each texel takes the part whose baked texels are nearest (covered texels
    first, then margin rings; ties go to the later part, as a later object
    overwrites an earlier one in Cycles). Returns (rgb (H, W, 3), written (H, W) bool).
    """
    best = np.full((height, width), margin + 1, np.int32)
    rgb = zeros((height, width, 3), np.float32)
    for value, mask in parts:
        dist = ring_distance(mask, margin)
        take = dist <= best
        take &= dist <= margin
        # Whole-array copies under a mask: boolean indexing gathers and
        # scatters element by element (several ms at 128², a small bake's share).
        np.copyto(rgb, value, where=take[..., None])
        np.copyto(best, dist, where=take)
    return rgb, best <= margin


def linear_to_srgb(x):
    x = np.clip(x, 0.0, None)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def prepare_image(target, parts, margin, clear):
    """A callable writing the composited bake into target.image (reads it now)."""
    image, w, h = target.image, target.width, target.height
    if tuple(image.size) != (w, h):
        raise ValueError(f'image "{target.name}" changed size during the bake')
    rgb, written = compose_image(parts, h, w, margin)
    if target.encoding == 'srgb':
        rgb = linear_to_srgb(rgb)
    elif target.encoding == 'raw':
        rgb = np.clip(rgb, 0.0, None)
    channels = image.channels
    if clear:
        pixels = zeros((h, w, channels), np.float32)
        if channels == 4:
            pixels[..., 3] = target.clear_alpha
    else:
        pixels = np.empty(h * w * channels, np.float32)
        image.pixels.foreach_get(pixels)
        pixels = pixels.reshape(h, w, channels)
    if channels >= 3:
        np.copyto(pixels[..., :3], rgb, where=written[..., None])
    else:  # grey images take the luminance-free mean
        np.copyto(pixels[..., 0], rgb.mean(axis=2), where=written)
    if channels == 4:
        np.copyto(pixels[..., 3], np.float32(1.0), where=written)
    flat = np.ascontiguousarray(pixels).ravel()

    def write():
        image.pixels.foreach_set(flat)
        image.update()
    return write


def corner_to_loops(parts, n_loops):
    """Per-loop RGB from CORNER bakes: parts is a list of (value (3T, 3), tri_loops (T, 3)).
    A loop shared by several loop triangles (polygons with more than 3 corners)
    takes its first triangle's corner, as Cycles does ("first triangle wins",
    object_bake_api bake_targets_populate_pixels_color_attributes): each corner
    is shaded just inside its own triangle, so the choice matters where another
    object meets the polygon. Returns (rgb (L, 3), has (L,) bool)."""
    rgb = np.zeros((n_loops, 3), np.float32)
    has = np.zeros(n_loops, bool)
    for value, tri_loops in parts:
        loops = np.asarray(tri_loops, np.int64).ravel()
        # np.unique's index is each loop's first occurrence in triangle order.
        unique, first = np.unique(loops, return_index=True)
        fresh = ~has[unique]
        rgb[unique[fresh]] = np.asarray(value, np.float32)[first[fresh]]
        has[unique[fresh]] = True
    return rgb, has


def prepare_attribute(target, parts):
    """A callable writing the bake into the active color attribute (reads it now)."""
    mesh = target.mesh
    attribute = mesh.color_attributes.get(target.attribute_name)
    if attribute is None:
        raise ValueError(f'color attribute "{target.attribute_name}" of "{target.object_name}" '
                         f'was removed during the bake')
    if len(mesh.loops) != target.n_loops or len(mesh.vertices) != target.n_verts:
        raise ValueError(f'"{target.object_name}" changed topology during the bake')
    loop_rgb, has = corner_to_loops(parts, target.n_loops)
    if target.domain == 'CORNER':
        rgb, write_mask = loop_rgb, has
        count = target.n_loops
    else:
        # Cycles: a vertex takes the mean of its loops' results.
        count = target.n_verts
        lv = target.loop_vertex[has]
        total = np.zeros((count, 3), np.float64)
        for c in range(3):
            total[:, c] = np.bincount(lv, weights=loop_rgb[has, c], minlength=count)
        n = np.bincount(lv, minlength=count)
        write_mask = n > 0
        total[write_mask] /= n[write_mask, None]
        rgb = total.astype(np.float32)
    if len(attribute.data) != count:
        raise ValueError(f'color attribute "{attribute.name}" has {len(attribute.data)} '
                         f'entries, expected {count}')
    colors = np.empty(count * 4, np.float32)
    attribute.data.foreach_get("color", colors)
    colors = colors.reshape(count, 4)
    colors[write_mask, :3] = np.clip(rgb[write_mask], 0.0, None)
    colors[write_mask, 3] = 1.0
    flat = colors.ravel()
    name = attribute.name

    def write():
        mesh.color_attributes[name].data.foreach_set("color", flat)
        mesh.update()
    return write
