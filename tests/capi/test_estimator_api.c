/* The estimator through the C ABI, from C: lifecycle, results, errors. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "omis/omis.h"

#include "check.h"

static OMISError callback_code = OMIS_ERROR_NONE;
static void on_error(void* user, OMISError code, const char* message) {
    (void)message;
    ++*(int*)user;
    callback_code = code;
}

/* Balance by hand: f/q summed over samples, divided by rounds. */
static void test_balance_matches_hand_computation(void) {
    const int counts[2] = {1, 2};
    const int technique[6] = {0, 1, 1, 0, 1, 1};
    const double pdfs[12] = {1.0, 0.5, 0.8, 1.2, 0.3, 0.9, 2.0, 0.1, 0.7, 0.7, 1.5, 0.2};
    const double f[6] = {0.4, 1.0, 0.2, 0.9, 0.5, 0.3};
    double expected = 0.0, estimate = 0.0, variance = -1.0;
    int s;
    OMISEstimator e = omisNewEstimator(OMIS_STRATEGY_BALANCE, 2, 1, counts);
    CHECK(e != NULL);
    omisCommitEstimator(e);
    CHECK(omisAddEstimatorSamples(e, 6, technique, sizeof(int), pdfs, 2 * sizeof(double), f,
                                  sizeof(double)));
    CHECK(omisGetEstimatorResult(e, &estimate, &variance));
    for (s = 0; s < 6; ++s) expected += f[s] / (pdfs[2 * s] + 2 * pdfs[2 * s + 1]);
    expected /= 2.0;
    CHECK(fabs(estimate - expected) <= 1e-14 * fabs(expected));
    CHECK(variance >= 0.0);
    omisReleaseEstimator(e);
    CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
}

static void test_errors(void) {
    const int counts[2] = {1, 1};
    const int bad_counts[2] = {-1, 1};
    const int technique[2] = {0, 1};
    const double pdfs[4] = {0.0, 1.0, 1.0, 1.0}; /* sample 0: own pdf is zero */
    const double f[2] = {1.0, 1.0};
    const char* message = NULL;
    double estimate;
    OMISStrategy strategy;
    OMISEstimator e;
    int calls = 0;

    /* NULL handles */
    omisReleaseEstimator(NULL);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT);
    CHECK(message != NULL && strstr(message, "NULL") != NULL);
    CHECK(omisGetError(NULL) == OMIS_ERROR_NONE); /* cleared by the query */

    /* invalid arguments at creation */
    CHECK(omisNewEstimator(OMIS_STRATEGY_BALANCE, 2, 1, bad_counts) == NULL);
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(message, "counts") != NULL);
    CHECK(omisNewEstimator((OMISStrategy)99, 2, 1, counts) == NULL);
    CHECK(omisGetError(NULL) == OMIS_ERROR_INVALID_ARGUMENT);

    /* wrong order: use before commit */
    e = omisNewEstimator(OMIS_STRATEGY_OPTIMAL_DIRECT, 2, 1, counts);
    CHECK(!omisGetEstimatorResult(e, &estimate, NULL));
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_OPERATION);
    CHECK(strstr(message, "commit") != NULL);

    /* the error callback sees every error */
    omisSetErrorFunction(on_error, &calls);
    omisSetEstimatorFloat(e, "no-such-option", 1.0);
    CHECK(calls == 1 && callback_code == OMIS_ERROR_INVALID_ARGUMENT);
    omisSetErrorFunction(NULL, NULL);
    CHECK(omisGetError(NULL) == OMIS_ERROR_INVALID_ARGUMENT);

    /* invalid samples */
    omisCommitEstimator(e);
    CHECK(!omisAddEstimatorSamples(e, 2, technique, sizeof(int), pdfs, 2 * sizeof(double), f,
                                   sizeof(double)));
    CHECK(omisGetError(&message) == OMIS_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(message, "own technique") != NULL && strstr(message, "sample 0") != NULL);
    /* no complete round: an operation error, not a crash */
    CHECK(!omisGetEstimatorResult(e, &estimate, NULL));
    CHECK(omisGetError(NULL) == OMIS_ERROR_INVALID_OPERATION);

    /* reference counting: retain keeps it alive across one release */
    omisRetainEstimator(e);
    omisReleaseEstimator(e);
    omisResetEstimator(e);
    CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
    omisReleaseEstimator(e);

    CHECK(omisParseStrategy("optimal-progressive", &strategy) &&
          strategy == OMIS_STRATEGY_OPTIMAL_PROGRESSIVE);
    CHECK(!omisParseStrategy("nonsense", &strategy));
}

int main(void) {
    CHECK(omisGetVersion() == OMIS_VERSION);
    test_balance_matches_hand_computation();
    test_errors();
    return check_summary();
}
