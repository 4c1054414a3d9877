/* A short example of the omis C API: a floor under a rectangular light,
 * baked into a 128×128 lightmap with optimal MIS and written to an EXR.
 *
 *   bake_floor [output.exr]
 */
#include <stdio.h>
#include <stdlib.h>

#include "omis/omis.h"

static void on_error(void* user, OMISError code, const char* message) {
    (void)user;
    fprintf(stderr, "omis error %d: %s\n", (int)code, message);
}

static bool on_progress(void* user, double fraction) {
    (void)user;
    (void)fraction;
    return true; /* return false to cancel */
}

int main(int argc, char** argv) {
    const char* path = argc > 1 ? argv[1] : "bake_floor.exr";
    /* A 4 m floor of two triangles at z = 0, with one UV per triangle corner. */
    const float vertices[] = {-2, -2, 0, 2, -2, 0, 2, 2, 0, -2, 2, 0};
    const uint32_t triangles[] = {0, 1, 2, 0, 2, 3};
    const float uvs[] = {0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 1};
    /* A 1 m × 0.5 m light 1.5 m up, facing down (cross(edgeU, edgeV) = −z). */
    const double corner[3] = {-0.5, -0.25, 1.5}, edgeU[3] = {0, 0.5, 0}, edgeV[3] = {1, 0, 0};
    const double radiance[3] = {10, 9, 8};
    const int counts[2] = {1, 1};
    OMISScene scene;
    OMISBake bake;
    OMISBakeResult result;
    OMISBakeStats stats;
    unsigned int floor;
    int ok = 1;

    printf("omis %s (library %d)\n", OMIS_VERSION_STRING, omisGetVersion());
    omisSetErrorFunction(on_error, NULL);

    scene = omisNewScene();
    floor = omisAddMesh(scene, vertices, OMIS_DATA_FLOAT32, 0, 4, triangles, 2, NULL, uvs,
                             NULL);
    omisAddRectLight(scene, corner, edgeU, edgeV, radiance, false, 3.14159265358979);
    omisCommitScene(scene);

    bake = omisNewBake(scene, OMIS_BAKE_LIGHTMAP, floor);
    omisSetBakeInt(bake, "width", 128);
    omisSetBakeInt(bake, "height", 128);
    omisSetBakeInt(bake, "samples", 64);
    omisSetBakeString(bake, "techniques", "uniform/solid-angle,uniform/area");
    omisSetBakeCounts(bake, counts, 2);
    omisSetBakeString(bake, "strategy", "optimal-direct");
    omisSetBakeProgressFunction(bake, on_progress, NULL);
    omisCommitBake(bake);

    result = omisExecuteBake(bake);
    if (result && omisGetBakeResultStats(result, &stats) && omisWriteBakeResultEXR(result, path)) {
        printf("baked %llu texels in %.2f s: %.0f samples/texel, mean relative error %.2f %%\n",
               (unsigned long long)stats.covered, stats.seconds, stats.samplesPerTexel,
               100 * stats.meanRelativeError);
        printf("wrote %s\n", path);
    } else {
        ok = 0;
    }

    if (result) omisReleaseBakeResult(result);
    omisReleaseBake(bake);
    omisReleaseScene(scene);
    return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
