/* Misuse of the C ABI (issue 11): out-of-range enums, bad bake options at
 * commit, double commits, foreign and released handles — each an error with
 * a message naming the argument, never undefined behaviour. */
#include <string.h>

#include "check.h"
#include "floor_scene.h"
#include "omis/omis.h"

/* AddressSanitizer reports any read of freed memory, which is what detecting a
 * released handle has to do; that part runs in the normal build only. */
#if defined(__SANITIZE_ADDRESS__)
#define OMIS_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define OMIS_TEST_ASAN 1
#endif
#endif

static void enums_out_of_range(OMISScene scene) {
    const int counts[2] = {1, 1};
    const float vertex[3] = {0, 0, 0};
    const uint32_t triangle[3] = {0, 0, 0};
    CHECK(omisNewEstimator((OMISStrategy)42, 2, 1, counts) == NULL);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "strategy"));
    CHECK(omisNewEstimator((OMISStrategy)-7, 2, 1, counts) == NULL);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "strategy"));
    CHECK(omisNewBake(scene, (OMISBakeTarget)99, 0) == NULL);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "target"));
    {
        OMISScene other = omisNewScene();
        CHECK(omisAddMesh(other, vertex, (OMISDataType)1000, 0, 1, triangle, 1, NULL, NULL,
                               NULL) == OMIS_INVALID_ID);
        CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "type"));
        omisReleaseScene(other);
    }
}

static void bake_options_checked_at_commit(OMISScene scene) {
    struct { const char* name; double value; } bad[] = {
        {"beta", -1}, {"cutoff", 2}, {"timeBudget", -1}, {"noiseTarget", -0.5}};
    size_t i;
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        OMISBake bake = omisNewBake(scene, OMIS_BAKE_VERTICES, 0);
        omisSetBakeFloat(bake, bad[i].name, bad[i].value);
        omisGetError(NULL); /* the setter may already refuse; commit must */
        omisCommitBake(bake);
        CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, bad[i].name));
        omisReleaseBake(bake);
    }
}

static void estimator_committed_once(void) {
    const int counts[2] = {1, 1};
    const int technique[2] = {0, 1};
    const double pdfs[4] = {1, 1, 1, 1}, f[2] = {1, 1};
    double estimate = 0;
    OMISEstimator e = omisNewEstimator(OMIS_STRATEGY_BALANCE, 2, 1, counts);
    omisCommitEstimator(e);
    CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
    CHECK(omisAddEstimatorSamples(e, 2, technique, sizeof(int), pdfs, 2 * sizeof(double), f,
                                  sizeof(double)));
    omisCommitEstimator(e); /* would drop the samples */
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "already committed"));
    CHECK(omisGetEstimatorResult(e, &estimate, NULL));
    CHECK(estimate == 1.0); /* both samples kept: f/q = 1/2 from each technique */
    omisReleaseEstimator(e);
}

static void foreign_and_released_handles(OMISScene scene) {
    /* A pointer to memory that is no omis object, and a handle of another kind. */
    static double not_a_handle[16];
    const int counts[1] = {1};
    OMISEstimator estimator = omisNewEstimator(OMIS_STRATEGY_BALANCE, 1, 1, counts);
    omisCommitScene((OMISScene)(void*)not_a_handle);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "not a live handle"));
    omisCommitBake((OMISBake)(void*)estimator);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "not a live handle"));
    CHECK(omisNewBake((OMISScene)(void*)estimator, OMIS_BAKE_VERTICES, 0) == NULL);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "not a live handle"));
    omisReleaseEstimator(estimator);
#ifndef OMIS_TEST_ASAN
    {
        /* Released: reported while the freed memory still reads back as such. */
        OMISBake bake = omisNewBake(scene, OMIS_BAKE_VERTICES, 0);
        OMISBakeResult result;
        omisCommitBake(bake);
        result = omisExecuteBake(bake);
        CHECK(result != NULL);
        omisReleaseBakeResult(result);
        CHECK(!omisWriteBakeResultEXR(result, "released.exr"));
        CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "not a live handle"));
        omisReleaseBake(bake);
        omisReleaseBake(bake); /* double release */
        CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "not a live handle"));
    }
#else
    (void)scene;
#endif
}

int main(void) {
    OMISScene scene = floor_scene(1);
    omisCommitScene(scene);
    enums_out_of_range(scene);
    bake_options_checked_at_commit(scene);
    estimator_committed_once();
    foreign_and_released_handles(scene);
    omisReleaseScene(scene);
    return check_summary();
}
