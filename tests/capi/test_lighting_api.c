/* The direct-lighting job of the C ABI (OMISDirectLighting), from C: every
 * parameter refused by name with a message naming it, the set → commit →
 * execute order, repeated executions, and bad points. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "floor_scene.h"
#include "lighting_job.h"
#include "omis/omis.h"

/* One call that must fail: which setter, the parameter name and value, and
 * the error it gives (code, a word of the message, and at which step). */
typedef enum { SET_INT, SET_FLOAT, SET_STRING, SET_COUNTS } Setter;

typedef struct {
    Setter setter;
    const char* name;     /* SET_COUNTS: unused */
    int64_t integer;      /* SET_INT */
    double real;          /* SET_FLOAT */
    const char* text;     /* SET_STRING */
    int num_counts;       /* SET_COUNTS: how many of kCounts (negative: as given) */
    const char* techniques; /* set first when not NULL */
    int at_commit;        /* the setter accepts it; commit refuses */
    const char* word;     /* the message names this */
} BadParameter;

static const int kCounts[3] = {1, -1, 2};

static const BadParameter kBad[] = {
    /* unknown names, and names given to another type's setter */
    {SET_INT, "round", 0, 0, NULL, 0, NULL, 0, "unknown integer direct-lighting parameter 'round'"},
    {SET_FLOAT, "gamma", 0, 1.0, NULL, 0, NULL, 0, "unknown float direct-lighting parameter 'gamma'"},
    {SET_STRING, "colour", 0, 0, "red", 0, NULL, 0, "unknown string direct-lighting parameter"},
    {SET_INT, "beta", 2, 0, NULL, 0, NULL, 0, "'beta' is a float parameter"},
    {SET_FLOAT, "rounds", 0, 4.0, NULL, 0, NULL, 0, "'rounds' is an integer parameter"},
    {SET_STRING, "seed", 0, 0, "7", 0, NULL, 0, "omisSetDirectLightingInt"},
    {SET_INT, NULL, 0, 0, NULL, 0, NULL, 0, "name"},
    /* values out of range */
    {SET_INT, "rounds", 0, 0, NULL, 0, NULL, 0, "rounds: 0 is out of range"},
    {SET_INT, "rounds", (int64_t)1 << 21, 0, NULL, 0, NULL, 0, "rounds"},
    {SET_FLOAT, "beta", 0, -1.0, NULL, 0, NULL, 0, "beta: must be a positive"},
    {SET_FLOAT, "beta", 0, NAN, NULL, 0, NULL, 0, "beta"},
    {SET_FLOAT, "cutoff", 0, 2.0, NULL, 0, NULL, 0, "cutoff: must lie in [0, 1]"},
    {SET_FLOAT, "cutoff", 0, NAN, NULL, 0, NULL, 0, "cutoff"},
    {SET_STRING, "strategy", 0, 0, "optimal", 0, NULL, 0, "strategy: unknown strategy 'optimal'"},
    {SET_STRING, "strategy", 0, 0, NULL, 0, NULL, 0, "strategy"},
    {SET_STRING, "techniques", 0, 0, "bsdf,uniform/areal", 0, NULL, 0, "'uniform/areal'"},
    {SET_STRING, "techniques", 0, 0, "bsdf,,uniform/area", 0, NULL, 0, "techniques: empty name"},
    {SET_COUNTS, NULL, 0, 0, NULL, -1, NULL, 0, "numCounts"},
    /* what only commit can see: counts against the list, techniques against each other */
    {SET_STRING, "techniques", 0, 0, "bsdf,bsdf", 0, NULL, 1, "twice"},
    {SET_COUNTS, NULL, 0, 0, NULL, 1, "bsdf,uniform/area", 1, "counts: expected 2 entries"},
    {SET_COUNTS, NULL, 0, 0, NULL, 2, "bsdf,uniform/area", 1, "counts: entry 1"},
    {SET_COUNTS, NULL, 0, 0, NULL, 1, NULL, 1, "counts: given without techniques"},
};

static void set(OMISDirectLighting job, const BadParameter* p) {
    if (p->techniques) omisSetDirectLightingString(job, "techniques", p->techniques);
    switch (p->setter) {
        case SET_INT: omisSetDirectLightingInt(job, p->name, p->integer); break;
        case SET_FLOAT: omisSetDirectLightingFloat(job, p->name, p->real); break;
        case SET_STRING: omisSetDirectLightingString(job, p->name, p->text); break;
        case SET_COUNTS: omisSetDirectLightingCounts(job, kCounts, p->num_counts); break;
    }
}

static void bad_parameters_are_named(OMISScene scene) {
    size_t i;
    for (i = 0; i < sizeof kBad / sizeof kBad[0]; ++i) {
        const BadParameter* p = &kBad[i];
        OMISDirectLighting job = omisNewDirectLighting(scene);
        set(job, p);
        if (p->at_commit) {
            CHECK(omisGetError(NULL) == OMIS_ERROR_NONE);
            omisCommitDirectLighting(job);
        }
        if (!error_is(OMIS_ERROR_INVALID_ARGUMENT, p->word)) {
            fprintf(stderr, "  row %d\n", (int)i);
            CHECK(0);
        }
        /* A refused value leaves the job as it was: the defaults still commit. */
        if (!p->at_commit) {
            omisCommitDirectLighting(job);
            CHECK(error_is(OMIS_ERROR_NONE, NULL));
        }
        omisReleaseDirectLighting(job);
    }
}

static void order_of_calls(OMISScene scene) {
    const double point[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    double value[3];
    OMISScene open_scene = floor_scene(0);
    OMISDirectLighting job = omisNewDirectLighting(open_scene);

    CHECK(omisNewDirectLighting(NULL) == NULL);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "scene"));
    CHECK(!omisExecuteDirectLighting(NULL, point, up, 1, value, NULL, NULL));
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "lighting"));
    /* a job on an uncommitted scene is made, but cannot commit */
    CHECK(job != NULL);
    omisCommitDirectLighting(job);
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "omisCommitScene"));
    CHECK(!omisExecuteDirectLighting(job, point, up, 1, value, NULL, NULL));
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "omisCommitDirectLighting"));
    omisReleaseDirectLighting(job);
    omisReleaseScene(open_scene);

    job = new_lighting(scene, NULL, NULL, 0, 2, "balance", 3);
    CHECK(error_is(OMIS_ERROR_NONE, NULL));
    omisCommitDirectLighting(job); /* a second commit does nothing */
    CHECK(error_is(OMIS_ERROR_NONE, NULL));
    omisSetDirectLightingInt(job, "rounds", 8);
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "after omisCommitDirectLighting"));
    omisSetDirectLightingCounts(job, NULL, 0);
    CHECK(error_is(OMIS_ERROR_INVALID_OPERATION, "after omisCommitDirectLighting"));
    /* the job holds its scene; retain keeps the job across one release */
    omisRetainDirectLighting(job);
    omisReleaseDirectLighting(job);
    CHECK(omisExecuteDirectLighting(job, point, up, 1, value, NULL, NULL));
    CHECK(error_is(OMIS_ERROR_NONE, NULL));
    /* a handle of another kind */
    omisCommitDirectLighting((OMISDirectLighting)(void*)scene);
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "not a live handle"));
    omisReleaseDirectLighting(job);
}

static void bad_points_are_named(OMISScene scene) {
    const double point[3] = {0, 0, 0}, up[3] = {0, 0, 1}, zero[3] = {0, 0, 0};
    const double nan_points[6] = {0, 0, 0, 0, NAN, 0}, ups[6] = {0, 0, 1, 0, 0, 1};
    double value[6], variance[6];
    OMISDirectLighting job = new_lighting(scene, NULL, NULL, 0, 1, "balance", 0);
    CHECK(!omisExecuteDirectLighting(job, nan_points, ups, 2, value, variance, NULL));
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "points: point 1"));
    CHECK(!omisExecuteDirectLighting(job, point, zero, 1, value, variance, NULL));
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "zero length"));
    CHECK(!omisExecuteDirectLighting(job, point, up, 1, NULL, variance, NULL));
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "value"));
    CHECK(!omisExecuteDirectLighting(job, NULL, up, 1, value, variance, NULL));
    CHECK(error_is(OMIS_ERROR_INVALID_ARGUMENT, "points"));
    /* count 0 succeeds without touching the arrays */
    CHECK(omisExecuteDirectLighting(job, NULL, NULL, 0, NULL, NULL, NULL));
    CHECK(error_is(OMIS_ERROR_NONE, NULL));
    omisReleaseDirectLighting(job);
}

/* Results are a function of the settings and seed: the same job executed
 * twice, and a second job with the same settings, agree to the bit; another
 * seed does not. */
static void executions_repeat(OMISScene scene) {
    const double points[6] = {0, 0, 0, 0.3, -0.2, 0}, normals[6] = {0, 0, 1, 0, 0, 1};
    const int counts[2] = {2, 2};
    double first[6], again[6], twin[6], other[6];
    OMISDirectLightingStats stats;
    OMISDirectLighting job = new_lighting(scene, "bsdf,uniform/area", counts, 2, 4,
                                          "optimal-direct", 42);
    OMISDirectLighting same = new_lighting(scene, "bsdf,uniform/area", counts, 2, 4,
                                           "optimal-direct", 42);
    OMISDirectLighting reseeded = new_lighting(scene, "bsdf,uniform/area", counts, 2, 4,
                                               "optimal-direct", 43);
    CHECK(omisExecuteDirectLighting(job, points, normals, 2, first, NULL, &stats));
    CHECK(stats.points == 2 && stats.samples == 2 * 4 * 4);
    CHECK(omisExecuteDirectLighting(job, points, normals, 2, again, NULL, NULL));
    CHECK(omisExecuteDirectLighting(same, points, normals, 2, twin, NULL, NULL));
    CHECK(omisExecuteDirectLighting(reseeded, points, normals, 2, other, NULL, NULL));
    CHECK(error_is(OMIS_ERROR_NONE, NULL));
    CHECK(memcmp(first, again, sizeof first) == 0);
    CHECK(memcmp(first, twin, sizeof first) == 0);
    CHECK(memcmp(first, other, sizeof first) != 0);
    omisReleaseDirectLighting(job);
    omisReleaseDirectLighting(same);
    omisReleaseDirectLighting(reseeded);
}

int main(void) {
    OMISScene scene = floor_scene(0);
    omisCommitScene(scene);
    bad_parameters_are_named(scene);
    order_of_calls(scene);
    bad_points_are_named(scene);
    executions_repeat(scene);
    omisReleaseScene(scene);
    return check_summary();
}
