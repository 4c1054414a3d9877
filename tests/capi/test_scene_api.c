/* Scenes and direct lighting through the C ABI, from C: lifecycle, errors,
 * a rect light against Lambert's formula, cancellation, the effect plan.
 * The direct-lighting job's own parameters and errors: test_lighting_api.c. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "omis/omis.h"

#include "check.h"
#include "lighting_job.h"

static const double kPi = 3.14159265358979323846;

/* ---- Lambert's formula (SPEC §5), written here independently ------------ */

static void sub(const double a[3], const double b[3], double out[3]) {
    out[0] = a[0] - b[0];
    out[1] = a[1] - b[1];
    out[2] = a[2] - b[2];
}
static void cross3(const double a[3], const double b[3], double out[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}
static double dot3(const double a[3], const double b[3]) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static double norm3(const double a[3]) { return sqrt(dot3(a, a)); }

/* E/L for a polygon wholly above x's horizon: (1/2) |Σ θ_e n·(v_e×v_{e+1})/|…||. */
static double lambert_polygon(const double x[3], const double n[3],
                              const double (*verts)[3], int count) {
    double sum = 0.0, u[4][3], c[3];
    int e, k;
    for (e = 0; e < count; ++e) {
        double len;
        sub(verts[e], x, u[e]);
        len = norm3(u[e]);
        for (k = 0; k < 3; ++k) u[e][k] /= len;
    }
    for (e = 0; e < count; ++e) {
        const double* a = u[e];
        const double* b = u[(e + 1) % count];
        double len;
        cross3(a, b, c);
        len = norm3(c);
        sum += atan2(len, dot3(a, b)) * dot3(n, c) / len;
    }
    return 0.5 * fabs(sum);
}

/* ---- Scenes -------------------------------------------------------------- */

/* A 1 × 0.5 m rectangle 1 m above the z = 0 plane, emitting downwards. */
static const double kCorner[3] = {-0.5, -0.25, 1.0};
static const double kEdgeU[3] = {0.0, 0.5, 0.0};
static const double kEdgeV[3] = {1.0, 0.0, 0.0}; /* cross(U, V) = −z: faces the floor */
static const double kRadiance[3] = {1.0, 2.0, 0.5};

static OMISScene rect_scene(void) {
    OMISScene scene = omisNewScene();
    CHECK(omisAddRectLight(scene, kCorner, kEdgeU, kEdgeV, kRadiance, false, kPi) ==
          0);
    omisCommitScene(scene);
    CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
    return scene;
}

static void test_errors(void) {
    const float quad[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const uint32_t tris[2][3] = {{0, 1, 2}, {0, 2, 3}};
    const uint32_t bad_tris[2][3] = {{0, 1, 2}, {0, 2, 4}};
    float nan_quad[4][3];
    const double zero_edge[3] = {0.0, 0.0, 0.0};
    const double point[3] = {0.0, 0.0, 0.0};
    const int samples[2] = {1, 1};
    char text[16];
    OMISScene scene;

    /* NULL handles */
    omisReleaseScene(NULL);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "NULL"));
    omisCommitScene(NULL);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "scene"));
    CHECK(omisAddRectLight(NULL, kCorner, kEdgeU, kEdgeV, kRadiance, false, kPi) ==
          OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "scene"));
    CHECK(omisNewDirectLighting(NULL) == NULL);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "scene"));
    CHECK(omisGetEffectPlan(NULL, NULL, NULL, text, sizeof text) == 0);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "scene"));

    scene = omisNewScene();
    CHECK(scene != NULL);

    /* invalid meshes */
    memcpy(nan_quad, quad, sizeof quad);
    nan_quad[2][1] = NAN;
    CHECK(omisAddMesh(scene, quad, OMIS_DATA_FLOAT32, 0, 4, &bad_tris[0][0], 2, NULL,
                           NULL, NULL) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "out of range"));
    CHECK(omisAddMesh(scene, nan_quad, OMIS_DATA_FLOAT32, 0, 4, &tris[0][0], 2, NULL,
                           NULL, NULL) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "vertex 2"));
    CHECK(omisAddMesh(scene, quad, (OMISDataType)7, 0, 4, &tris[0][0], 2, NULL, NULL,
                           NULL) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "type"));
    CHECK(omisAddMesh(scene, quad, OMIS_DATA_FLOAT32, 4, 4, &tris[0][0], 2, NULL,
                           NULL, NULL) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "vertexByteStride"));
    CHECK(omisAddMesh(scene, quad, OMIS_DATA_FLOAT32, 0, 4, NULL, 2, NULL, NULL,
                           NULL) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "triangles"));

    /* invalid lights */
    CHECK(omisAddRectLight(scene, kCorner, kEdgeU, zero_edge, kRadiance, false,
                                kPi) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, NULL));
    CHECK(omisAddRectLight(scene, kCorner, NULL, kEdgeV, kRadiance, false, kPi) ==
          OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "edgeU"));
    CHECK(omisAddPointLight(scene, point, kRadiance, -1.0) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, NULL));

    /* a valid mesh (its id is 0: failed adds leave no trace) and light */
    CHECK(omisAddMesh(scene, quad, OMIS_DATA_FLOAT32, 0, 4, &tris[0][0], 2, NULL,
                           NULL, NULL) == 0);
    CHECK(omisAddRectLight(scene, kCorner, kEdgeU, kEdgeV, kRadiance, false, kPi) ==
          0);
    omisSetLightFlags(scene, 5, true, true);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "light"));

    /* use before commit */
    omisReleaseDirectLighting(new_lighting(scene, NULL, NULL, 0, 1, "balance", 0));
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "commit"));
    CHECK(omisGetEffectPlan(scene, NULL, NULL, text, sizeof text) == 0);
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "commit"));

    /* add after commit */
    omisCommitScene(scene);
    omisCommitScene(scene); /* a second commit does nothing */
    CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
    CHECK(omisAddRectLight(scene, kCorner, kEdgeU, kEdgeV, kRadiance, false, kPi) ==
          OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "committed"));
    CHECK(omisAddMesh(scene, quad, OMIS_DATA_FLOAT32, 0, 4, &tris[0][0], 2, NULL,
                           NULL, NULL) == OMIS_INVALID_ID);
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "committed"));
    omisSetLightFlags(scene, 0, false, true);
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "committed"));
    omisSetMeshLights(scene, false);
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "committed"));

    CHECK(omisGetEffectPlan(scene, "nope", samples, text, sizeof text) == 0);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "'nope'"));

    /* reference counting: retain keeps it alive across one release */
    omisRetainScene(scene);
    omisReleaseScene(scene);
    CHECK(omisGetEffectPlan(scene, NULL, NULL, NULL, 0) > 0);
    CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
    omisReleaseScene(scene);
}

/* A rect light over receivers on the floor: E/π from Lambert's formula. */
static void test_rect_light_matches_lambert(void) {
    /* the receivers: under the light, off to the side, tilted */
    const double points[4][3] = {
        {0.0, 0.0, 0.0}, {0.3, -0.2, 0.0}, {1.5, 0.5, 0.0}, {0.1, 0.1, 0.2}};
    double normals[4][3] = {
        {0.0, 0.0, 1.0}, {0.0, 0.0, 1.0}, {0.0, 0.0, 1.0}, {0.3, 0.0, 1.0}};
    const char* techniques[3] = {"bsdf,uniform/solid-angle",
                                 "uniform/area,unoccluded/parallel", NULL};
    const int samples[2] = {4, 4};
    const char* strategies[3] = {"optimal-direct", "balance", "optimal-progressive"};
    double verts[4][3], value[12], variance[12], unit[3];
    OMISDirectLightingStats stats;
    OMISScene scene = rect_scene();
    int i, k, t;

    for (k = 0; k < 3; ++k) {
        verts[0][k] = kCorner[k];
        verts[1][k] = kCorner[k] + kEdgeU[k];
        verts[2][k] = kCorner[k] + kEdgeU[k] + kEdgeV[k];
        verts[3][k] = kCorner[k] + kEdgeV[k];
    }
    for (t = 0; t < 3; ++t) {
        OMISDirectLighting job =
            new_lighting(scene, techniques[t], samples, 2, 32, strategies[t], 1234 + t);
        CHECK(omisExecuteDirectLighting(job, &points[0][0], &normals[0][0], 4, value,
                                        variance, &stats));
        CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
        omisReleaseDirectLighting(job);
        CHECK(stats.points == 4);
        CHECK(stats.samples > 0 && stats.misSystems == 4);
        CHECK(stats.raysTraced == 0); /* no geometry: no shadow rays */
        for (i = 0; i < 4; ++i) {
            const double len = norm3(normals[i]);
            double e;
            for (k = 0; k < 3; ++k) unit[k] = normals[i][k] / len;
            e = lambert_polygon(points[i], unit, (const double(*)[3])verts, 4);
            for (k = 0; k < 3; ++k) {
                const double expected = kRadiance[k] * e / kPi;
                const double got = value[3 * i + k];
                const double tolerance = 4.0 * sqrt(variance[3 * i + k]) + 1e-9;
                if (!(fabs(got - expected) <= tolerance))
                    fprintf(stderr,
                            "  techniques %s point %d channel %d: %.6g vs %.6g ± %.3g\n",
                            techniques[t] ? techniques[t] : "(default)", i, k, got,
                            expected, tolerance);
                CHECK(fabs(got - expected) <= tolerance);
                CHECK(variance[3 * i + k] >= 0.0);
            }
        }
    }
    omisReleaseScene(scene);
}

/* Packed float64 vertices with a stride, and per-corner normals: a floor
 * under the rect light shadows nothing above it, and costs shadow rays. */
static void test_strided_mesh_and_shadow_rays(void) {
    /* each vertex row: x y z + one padding double */
    const double floor4[4][4] = {
        {-5, -5, -0.5, 9}, {5, -5, -0.5, 9}, {5, 5, -0.5, 9}, {-5, 5, -0.5, 9}};
    const uint32_t tris[2][3] = {{0, 1, 2}, {0, 2, 3}};
    double corner_normals[6][3];
    const double point[3] = {0.0, 0.0, 0.0}, up[3] = {0.0, 0.0, 2.0}; /* not unit */
    const int samples[1] = {8};
    double value[3], variance[3];
    OMISDirectLightingStats stats;
    OMISDirectLighting job;
    OMISScene scene = omisNewScene();
    int c;
    for (c = 0; c < 6; ++c) {
        corner_normals[c][0] = 0.0;
        corner_normals[c][1] = 0.0;
        corner_normals[c][2] = 1.0;
    }
    CHECK(omisAddMesh(scene, floor4, OMIS_DATA_FLOAT64, sizeof floor4[0], 4,
                           &tris[0][0], 2, corner_normals, NULL, NULL) == 0);
    CHECK(omisAddRectLight(scene, kCorner, kEdgeU, kEdgeV, kRadiance, false, kPi) ==
          0);
    omisCommitScene(scene);
    job = new_lighting(scene, "unoccluded/solid-angle", samples, 1, 4, "optimal-direct", 7);
    CHECK(omisExecuteDirectLighting(job, point, up, 1, value, variance, &stats));
    CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
    omisReleaseDirectLighting(job);
    CHECK(stats.raysTraced > 0);
    CHECK(value[0] > 0.0 && value[1] > value[0]);
    omisReleaseScene(scene);
}

static int progress_calls = 0;
static bool stop_at_once(void* user, double fraction) {
    (void)user;
    (void)fraction;
    ++progress_calls; /* called under the core's lock: no race on this counter */
    return false;
}

static void test_cancellation(void) {
    enum { kPoints = 4096 };
    double* points = malloc(sizeof(double) * 3 * kPoints);
    double* normals = malloc(sizeof(double) * 3 * kPoints);
    double* value = malloc(sizeof(double) * 3 * kPoints);
    const int samples[2] = {8, 8};
    OMISDirectLightingStats stats;
    OMISDirectLighting job;
    OMISScene scene = rect_scene();
    int i;
    for (i = 0; i < kPoints; ++i) {
        points[3 * i + 0] = (i % 64) / 64.0 - 0.5;
        points[3 * i + 1] = (i / 64) / 64.0 - 0.5;
        points[3 * i + 2] = 0.0;
        normals[3 * i + 0] = 0.0;
        normals[3 * i + 1] = 0.0;
        normals[3 * i + 2] = 1.0;
    }
    job = new_lighting(scene, "bsdf,uniform/area", samples, 2, 4, "optimal-direct", 0);
    omisSetDirectLightingProgressFunction(job, stop_at_once, NULL);
    CHECK(!omisExecuteDirectLighting(job, points, normals, kPoints, value, NULL, &stats));
    CHECK(error_is(OMIS_ERROR_CANCELLED, "cancel"));
    omisReleaseDirectLighting(job);
    CHECK(progress_calls >= 1);
    CHECK(stats.points < kPoints);
    omisReleaseScene(scene);
    free(points);
    free(normals);
    free(value);
}

static void test_effect_plan(void) {
    const int samples[3] = {4, 2, 0};
    const char* techniques = "power/solid-angle, power/area,bsdf";
    OMISScene scene = rect_scene();
    size_t length, length_default;
    char* text;
    char small[8];

    length = omisGetEffectPlan(scene, techniques, samples, NULL, 0);
    CHECK(length > 0);
    text = malloc(length + 1);
    CHECK(omisGetEffectPlan(scene, techniques, samples, text, length + 1) == length);
    CHECK(strlen(text) == length);
    CHECK(strstr(text, "power/solid-angle") != NULL && strstr(text, "bsdf") != NULL);
    CHECK(strstr(text, "shadow rays: no") != NULL);
    /* truncated, still NUL-terminated */
    CHECK(omisGetEffectPlan(scene, techniques, samples, small, sizeof small) == length);
    CHECK(strlen(small) == sizeof small - 1 &&
          strncmp(small, text, sizeof small - 1) == 0);
    /* the default choice */
    length_default = omisGetEffectPlan(scene, "", NULL, NULL, 0);
    CHECK(length_default > 0);
    CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
    free(text);
    omisReleaseScene(scene);
}

int main(void) {
    CHECK(omisGetVersion() == OMIS_VERSION);
    test_errors();
    test_rect_light_matches_lambert();
    test_strided_mesh_and_shadow_rays();
    test_cancellation();
    test_effect_plan();
    return check_summary();
}
