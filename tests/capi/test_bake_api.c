/* Bake jobs through the C ABI, from C: order errors, bad parameters, results,
 * atomic files and cancellation. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "omis/omis.h"

#include "check.h"
#include "floor_scene.h"

static int progress_calls = 0;
static bool cancel_at_ten_percent(void* user, double fraction) {
    (void)user;
    ++progress_calls;
    return fraction < 0.1;
}

int main(void) {
    const char* message = NULL;
    OMISScene scene = floor_scene(1);
    OMISBake bake;
    OMISBakeResult result;
    OMISBakeStats stats;
    OMISBakeWork work;
    int width = 0, height = 0;
    const float* value;
    FILE* f;

    /* NULL handles and wrong order */
    CHECK(omisNewBake(NULL, OMIS_BAKE_LIGHTMAP, 0) == NULL);
    CHECK(omisGetError(NULL) == OMIS_ERROR_INVALID_ARGUMENT);
    bake = omisNewBake(scene, OMIS_BAKE_LIGHTMAP, 0);
    CHECK(bake != NULL);
    omisCommitBake(bake); /* scene not committed yet */
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_OPERATION);
    CHECK(message && strstr(message, "not committed"));
    CHECK(omisExecuteBake(bake) == NULL);
    CHECK(omisGetError(NULL) == OMIS_ERROR_INVALID_OPERATION);
    omisCommitScene(scene);

    /* bad parameters name themselves */
    omisSetBakeInt(bake, "width", -3);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "width"));
    omisSetBakeInt(bake, "no-such-parameter", 1);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT &&
          strstr(message, "no-such-parameter"));
    omisCommitBake(bake); /* no width/height for a lightmap */
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "width"));
    omisSetBakeInt(bake, "width", 32);
    omisSetBakeInt(bake, "height", 16);
    omisSetBakeInt(bake, "samples", 16);
    omisSetBakeString(bake, "techniques", "uniform/solid-angle,uniform/sphere");
    omisCommitBake(bake);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT &&
          strstr(message, "uniform/sphere"));
    omisSetBakeString(bake, "techniques", "");
    omisCommitBake(bake);
    CHECK(omisGetError(&message) == OMIS_ERROR_NONE);
    omisSetBakeInt(bake, "samples", 8); /* after commit */
    CHECK(omisGetError(NULL) == OMIS_ERROR_INVALID_OPERATION);

    /* a result */
    result = omisExecuteBake(bake);
    CHECK(result != NULL);
    CHECK(omisGetBakeResultSize(result, &width, &height) && width == 32 && height == 16);
    value = omisGetBakeResultData(result, "value");
    CHECK(value != NULL && value[3 * (8 * 32 + 16)] > 0 && isfinite(value[0]));
    CHECK(omisGetBakeResultData(result, "colour") == NULL);
    CHECK(omisGetError(NULL) == OMIS_ERROR_INVALID_ARGUMENT);
    CHECK(omisGetBakeResultStats(result, &stats) && stats.covered == 32 * 16 &&
          stats.samplesPerTexel > 0);
    /* one light, no shadow: every texel draws its schedule's samples, no more */
    CHECK(omisGetBakeResultWork(result, &work) && work.shadowedTexels == 0 &&
          work.draws == stats.samples && work.drawsPerTexel == stats.samplesPerTexel);
    CHECK(!omisGetBakeResultWork(result, NULL));
    CHECK(omisGetError(NULL) == OMIS_ERROR_INVALID_ARGUMENT);
    CHECK(omisGetBakeResultPlan(result, NULL, 0) > 0);

    /* files: a failed write leaves the old file as it was */
    CHECK(omisWriteBakeResultEXR(result, "capi_bake_test.exr"));
    CHECK(!omisWriteBakeResultPNG(result, "capi_bake_test.exr", "No Such View", NULL, 0));
    CHECK(omisGetError(NULL) == OMIS_ERROR_INVALID_ARGUMENT);
    f = fopen("capi_bake_test.exr", "rb");
    CHECK(f != NULL);
    if (f) {
        char magic[4] = {0};
        CHECK(fread(magic, 1, 4, f) == 4 && magic[0] == 0x76 && magic[1] == 0x2f);
        fclose(f);
    }
    remove("capi_bake_test.exr");
    omisReleaseBakeResult(result);
    omisReleaseBake(bake);

    /* cancellation: a false from the progress function stops the bake */
    bake = omisNewBake(scene, OMIS_BAKE_LIGHTMAP, 0);
    omisSetBakeInt(bake, "width", 96);
    omisSetBakeInt(bake, "height", 96);
    omisSetBakeInt(bake, "samples", 1024);
    omisSetBakeProgressFunction(bake, cancel_at_ten_percent, NULL);
    omisCommitBake(bake);
    CHECK(omisExecuteBake(bake) == NULL);
    CHECK(omisGetError(&message) == OMIS_ERROR_CANCELLED);
    CHECK(progress_calls > 0);
    omisReleaseBake(bake);

    /* a mesh without UVs cannot be baked into a lightmap, but at its vertices */
    omisReleaseScene(scene);
    scene = floor_scene(0);
    omisCommitScene(scene);
    bake = omisNewBake(scene, OMIS_BAKE_LIGHTMAP, 0);
    omisSetBakeInt(bake, "width", 8);
    omisSetBakeInt(bake, "height", 8);
    omisCommitBake(bake);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "no UV map"));
    omisReleaseBake(bake);
    bake = omisNewBake(scene, OMIS_BAKE_VERTICES, 0);
    omisCommitBake(bake);
    result = omisExecuteBake(bake);
    CHECK(result && omisGetBakeResultSize(result, &width, &height) && width == 4 && height == 1);
    if (result) omisReleaseBakeResult(result);
    omisReleaseBake(bake);
    omisReleaseScene(scene);

    return check_summary();
}
