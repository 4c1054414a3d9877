/* An image-based world through the C ABI, from C: omisSetWorldImage with a
 * row stride, against the constant world it equals when constant, and its
 * errors (NULL data, sizes, strides, bad texels, rotation, unreadable files). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "omis/omis.h"

#include "check.h"
#include "lighting_job.h"

enum { kWidth = 16, kHeight = 8, kPadded = kWidth * 3 + 5 };

/* A constant map in rows padded to kPadded floats (the stride test). */
static void fill_constant(float* rows, const double c[3]) {
    int r, i, k;
    for (r = 0; r < kHeight; ++r)
        for (i = 0; i < kPadded; ++i) rows[r * kPadded + i] = -1.0f; /* padding: never read */
    for (r = 0; r < kHeight; ++r)
        for (i = 0; i < kWidth; ++i)
            for (k = 0; k < 3; ++k) rows[r * kPadded + i * 3 + k] = (float)c[k];
}

/* E/π at 16 up-facing points under a constant map: each value equals the
 * radiance (cosine draws of a constant world integrate it exactly: f/p = L). */
static void test_constant_map_lights_like_the_constant_world(void) {
    static float rows[kHeight * kPadded];
    const double c[3] = {0.75, 1.5, 0.25}, rotation[3] = {0.1, -0.4, 2.0};
    double points[16 * 3] = {0}, normals[16 * 3] = {0}, value[16 * 3];
    const int counts[1] = {8};
    OMISScene scene = omisNewScene();
    OMISDirectLighting job;
    int i, k;
    fill_constant(rows, c);
    CHECK(omisSetWorldImage(scene, rows, kWidth, kHeight, kPadded * sizeof(float), rotation,
                            false) != OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_NONE, NULL));
    omisCommitScene(scene);
    for (i = 0; i < 16; ++i) normals[3 * i + 2] = 1.0;
    job = new_lighting(scene, "bsdf", counts, 1, 1, "balance", 3);
    CHECK(omisExecuteDirectLighting(job, points, normals, 16, value, NULL, NULL));
    for (i = 0; i < 16; ++i)
        for (k = 0; k < 3; ++k) CHECK(fabs(value[3 * i + k] - c[k]) <= 1e-12 * c[k]);
    omisReleaseDirectLighting(job);
    omisReleaseScene(scene);
}

static void test_errors(void) {
    static float rows[kHeight * kPadded];
    const double c[3] = {1, 1, 1}, bad_rotation[3] = {0, NAN, 0};
    OMISScene scene = omisNewScene();
    fill_constant(rows, c);
    CHECK(omisSetWorldImage(scene, NULL, kWidth, kHeight, 0, NULL, false) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "rgb"));
    CHECK(omisSetWorldImage(scene, rows, 0, kHeight, 0, NULL, false) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "width and height"));
    CHECK(omisSetWorldImage(scene, rows, kWidth, kHeight, 7, NULL, false) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "rowByteStride"));
    CHECK(omisSetWorldImage(scene, rows, kWidth, kHeight, kPadded * sizeof(float), bad_rotation,
                            false) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "rotation"));
    rows[2 * kPadded + 3 * 3 + 1] = NAN;
    CHECK(omisSetWorldImage(scene, rows, kWidth, kHeight, kPadded * sizeof(float), NULL, false) ==
          OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "row 2, column 3, channel 1) is NaN"));
    rows[2 * kPadded + 3 * 3 + 1] = -2.0f;
    CHECK(omisSetWorldImage(scene, rows, kWidth, kHeight, kPadded * sizeof(float), NULL, true) ==
          OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "negative"));
    rows[2 * kPadded + 3 * 3 + 1] = (float)INFINITY;
    CHECK(omisSetWorldImage(scene, rows, kWidth, kHeight, kPadded * sizeof(float), NULL, true) ==
          OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "infinite"));
    CHECK(omisSetWorldImageFile(scene, "/nonexistent/sky.exr", NULL, false) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "/nonexistent/sky.exr"));
    CHECK(omisSetWorldImageFile(scene, NULL, NULL, false) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "path"));
    omisCommitScene(scene);
    fill_constant(rows, c);
    CHECK(omisSetWorldImage(scene, rows, kWidth, kHeight, kPadded * sizeof(float), NULL, false) ==
          OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "committed"));
    omisReleaseScene(scene);
}

int main(void) {
    test_constant_map_lights_like_the_constant_world();
    test_errors();
    return check_summary();
}
