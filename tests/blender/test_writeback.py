"""Write-back (omis_bake/writeback.py) against a texel-by-texel reference:
compose_image picks, per texel, the part whose baked texels are nearest (its
ring distance, ties to the later part, none beyond the margin); prepare_image
writes those texels (RGB, grey as the mean, alpha 1) over a cleared image or
the image's own pixels and leaves every other texel as it was.

    scripts/blender_run.sh tests/blender/test_writeback.py
"""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import omis_test_utils as U  # noqa: E402

from omis_bake import writeback  # noqa: E402

check = U.check


def reference_compose(parts, height, width, margin):
    dists = [writeback.ring_distance(mask, margin) for _, mask in parts]
    rgb = np.zeros((height, width, 3), np.float32)
    written = np.zeros((height, width), bool)
    for y in range(height):
        for x in range(width):
            best, chosen = margin + 1, None
            for k, dist in enumerate(dists):
                if dist[y, x] <= best and dist[y, x] <= margin:
                    best, chosen = dist[y, x], k
            if chosen is not None:
                rgb[y, x] = parts[chosen][0][y, x]
                written[y, x] = True
    return rgb, written


class FakePixels:
    def __init__(self, values):
        self.values = values

    def foreach_get(self, out):
        out[:] = self.values

    def foreach_set(self, values):
        self.values = np.array(values, np.float32)


class FakeImage:
    def __init__(self, width, height, channels, rng):
        self.size = (width, height)
        self.channels = channels
        self.pixels = FakePixels(rng.random(width * height * channels, dtype=np.float32))

    def update(self):
        pass


class FakeTarget:
    def __init__(self, image, clear_alpha):
        self.image, self.name = image, "fake"
        self.width, self.height = image.size
        self.encoding = 'float'
        self.clear_alpha = clear_alpha


def main():
    rng = np.random.default_rng(7)
    height, width = 23, 31
    for margin in (0, 2):
        # Three parts: sparse masks that overlap and leave gaps for the margin.
        parts = [(rng.random((height, width, 3), dtype=np.float32),
                  (rng.random((height, width)) < 0.2).astype(np.float32)) for _ in range(3)]
        got_rgb, got_written = writeback.compose_image(parts, height, width, margin)
        want_rgb, want_written = reference_compose(parts, height, width, margin)
        check(np.array_equal(got_written, want_written), f"margin {margin}: other texels written")
        check(np.array_equal(got_rgb[want_written], want_rgb[want_written]),
              f"margin {margin}: other values composed")
        for channels in (1, 3, 4):
            for clear in (False, True):
                image = FakeImage(width, height, channels, rng)
                before = image.pixels.values.reshape(height, width, channels).copy()
                writeback.prepare_image(FakeTarget(image, 0.0), parts, margin, clear)()
                after = image.pixels.values.reshape(height, width, channels)
                expected = before.copy()
                if clear:
                    expected[:] = 0.0
                for y, x in zip(*np.nonzero(want_written)):
                    if channels >= 3:
                        expected[y, x, :3] = want_rgb[y, x]
                    else:
                        expected[y, x, 0] = want_rgb[y, x].mean()
                    if channels == 4:
                        expected[y, x, 3] = 1.0
                check(np.allclose(after, expected, rtol=1e-6, atol=0),
                      f"margin {margin}, {channels} channels, clear={clear}: other pixels")
    U.log("test_writeback: ok")


main()
