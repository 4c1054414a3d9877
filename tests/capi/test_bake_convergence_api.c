/* A bake's convergence through the C ABI, from C: the per-pass history of a
 * result, its halving prediction, and omisPredictBakeHalving on synthetic
 * histories (exact power laws, too few passes, bad input). */
#include <math.h>
#include <string.h>

#include "omis/omis.h"

#include "check.h"
#include "floor_scene.h"

static void power_law(OMISBakePass* passes, int n, double beta) {
    int i;
    for (i = 0; i < n; ++i) {
        passes[i].seconds = 0.1 * pow(2.0, i);
        passes[i].samplesPerTexel = 16.0 * pow(2.0, i);
        passes[i].meanRelativeError = 0.3 * pow(passes[i].seconds, -beta);
    }
}

static void synthetic(void) {
    OMISBakePass passes[6];
    OMISBakeHalving h;
    const char* message = NULL;
    power_law(passes, 6, 0.75);
    CHECK(omisPredictBakeHalving(passes, 6, &h));
    CHECK(fabs(h.beta - 0.75) < 1e-9 && h.passesFitted == 4);
    CHECK(fabs(h.seconds - 3.2 * (pow(2.0, 1 / 0.75) - 1)) < 1e-9);
    /* Two passes: both fitted. One: beta = 0.5 assumed (3× the time again). */
    CHECK(omisPredictBakeHalving(passes, 2, &h));
    CHECK(h.passesFitted == 2 && fabs(h.beta - 0.75) < 1e-9);
    CHECK(omisPredictBakeHalving(passes, 1, &h));
    CHECK(h.passesFitted == 0 && h.beta == 0.5 && fabs(h.seconds - 0.3) < 1e-12);
    /* A second pass of a few more samples (a sample budget's last round) says
     * nothing about the rate. */
    passes[1].samplesPerTexel = 1.2 * passes[0].samplesPerTexel;
    CHECK(omisPredictBakeHalving(passes, 2, &h) && h.passesFitted == 0);
    power_law(passes, 6, 0.75);
    CHECK(omisPredictBakeHalving(NULL, 0, &h) && h.seconds == 0 && h.passesFitted == 0);
    /* Bad input names the argument. */
    CHECK(!omisPredictBakeHalving(NULL, 3, &h));
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "passes"));
    CHECK(!omisPredictBakeHalving(passes, -1, &h));
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "numPasses"));
    CHECK(!omisPredictBakeHalving(passes, 6, NULL));
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "halving"));
    passes[3].seconds = NAN;
    CHECK(!omisPredictBakeHalving(passes, 6, &h));
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "passes"));
}

static OMISBakeResult run(OMISScene scene, double noise_target) {
    OMISBakeResult result;
    OMISBake bake = omisNewBake(scene, OMIS_BAKE_LIGHTMAP, 0);
    omisSetBakeInt(bake, "width", 16);
    omisSetBakeInt(bake, "height", 16);
    omisSetBakeInt(bake, "samples", 4096);
    omisSetBakeString(bake, "strategy", "balance");
    if (noise_target > 0) omisSetBakeFloat(bake, "noiseTarget", noise_target);
    omisCommitBake(bake);
    result = omisExecuteBake(bake);
    omisReleaseBake(bake);
    return result;
}

static void from_a_bake(void) {
    OMISScene scene = floor_scene(1);
    OMISBakePass passes[64];
    OMISBakeHalving h, again;
    OMISBakeStats stats;
    const char* message = NULL;
    int n, i;
    omisCommitScene(scene);
    /* A sample budget alone: one pass (and a second, of one round, holding the
     * rest when the rounds do not divide the budget), the bound. */
    OMISBakeResult result = run(scene, 0);
    CHECK(result != NULL);
    n = omisGetBakeResultConvergence(result, NULL, 0);
    CHECK(n == 1 || n == 2);
    CHECK(omisGetBakeResultHalving(result, &h) && h.passesFitted == 0 && h.beta == 0.5);
    omisReleaseBakeResult(result);
    /* A noise target: passes, with samples and time growing and the last record
     * the result's own mean error; the stored prediction is the fit of them. */
    result = run(scene, 0.002);
    CHECK(result != NULL && omisGetBakeResultStats(result, &stats));
    n = omisGetBakeResultConvergence(result, passes, 64);
    CHECK(n == stats.passes && n >= 3 && n <= 64);
    for (i = 1; i < n && i < 64; ++i)
        CHECK(passes[i].seconds > passes[i - 1].seconds &&
              passes[i].samplesPerTexel > passes[i - 1].samplesPerTexel);
    CHECK(n >= 1 && passes[n - 1].meanRelativeError == stats.meanRelativeError);
    CHECK(omisGetBakeResultHalving(result, &h));
    CHECK(omisPredictBakeHalving(passes, n, &again));
    CHECK(again.beta == h.beta && again.seconds == h.seconds &&
          again.passesFitted == h.passesFitted);
    /* Capacity smaller than the history: the count is still the whole history. */
    CHECK(omisGetBakeResultConvergence(result, passes, 1) == n);
    CHECK(omisGetBakeResultConvergence(result, NULL, 2) == -1);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "passes"));
    CHECK(omisGetBakeResultConvergence(NULL, passes, 2) == -1);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT && strstr(message, "result"));
    CHECK(!omisGetBakeResultHalving(result, NULL));
    omisReleaseBakeResult(result);
    omisReleaseScene(scene);
}

int main(void) {
    synthetic();
    from_a_bake();
    return check_summary();
}
