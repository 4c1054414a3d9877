/* The C tests' direct-lighting job: set up and committed in one call. */
#ifndef OMIS_TESTS_LIGHTING_JOB_H
#define OMIS_TESTS_LIGHTING_JOB_H

#include <stddef.h>

#include "omis/omis.h"

/* A job on scene, committed: techniques NULL chooses the effect plan's (counts
 * then unused), else numCounts counts per round; rounds, strategy and seed as
 * named. A failed step leaves its error pending (the first one is kept) and
 * the job uncommitted; NULL only when the job could not be created. */
static OMISDirectLighting new_lighting(OMISScene scene, const char* techniques,
                                       const int* counts, int numCounts, int rounds,
                                       const char* strategy, int64_t seed) {
    OMISDirectLighting job = omisNewDirectLighting(scene);
    if (!job) return NULL;
    if (techniques) {
        omisSetDirectLightingString(job, "techniques", techniques);
        omisSetDirectLightingCounts(job, counts, numCounts);
    }
    omisSetDirectLightingInt(job, "rounds", rounds);
    omisSetDirectLightingString(job, "strategy", strategy);
    omisSetDirectLightingInt(job, "seed", seed);
    omisCommitDirectLighting(job);
    return job;
}

#endif
