/* omis — optimal multiple importance sampling for baked direct lighting.
 *
 * The stable plain-C interface to the omis library. Objects are opaque,
 * reference-counted handles: omisNewX creates one with a count of 1,
 * omisRetainX adds a reference, omisReleaseX drops one and frees the object
 * when none is left. Parameters are set, then the object is committed, then it
 * is used; using an uncommitted object is an error.
 *
 * Errors: a failing call returns an "invalid" value (NULL, false, 0) and
 * records an error code and message for the calling thread; omisGetError
 * returns the first error since the previous query and clears it. An optional
 * error callback is called for every error, from the thread that raised it.
 * No C++ exception crosses this interface.
 */
#ifndef OMIS_H
#define OMIS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define OMIS_VERSION_MAJOR 0
#define OMIS_VERSION_MINOR 1
#define OMIS_VERSION_PATCH 0
#define OMIS_VERSION (OMIS_VERSION_MAJOR * 10000 + OMIS_VERSION_MINOR * 100 + OMIS_VERSION_PATCH)
#define OMIS_VERSION_STRING "0.1.0"

#if defined(_WIN32)
#define OMIS_API_EXPORT __declspec(dllexport)
#else
#define OMIS_API_EXPORT __attribute__((visibility("default")))
#endif

#ifdef __cplusplus
#define OMIS_API extern "C" OMIS_API_EXPORT
#else
#define OMIS_API OMIS_API_EXPORT
#endif

/* ---- Errors and version ------------------------------------------------- */

typedef enum OMISError {
    OMIS_ERROR_NONE = 0,
    OMIS_ERROR_UNKNOWN = 1,
    OMIS_ERROR_INVALID_ARGUMENT = 2,
    OMIS_ERROR_INVALID_OPERATION = 3, /* wrong order, e.g. use before commit */
    OMIS_ERROR_OUT_OF_MEMORY = 4,
    OMIS_ERROR_UNSUPPORTED = 5,
    OMIS_ERROR_CANCELLED = 6
} OMISError;

typedef void (*OMISErrorFunction)(void* user, OMISError code, const char* message);

/* Packed version of the library actually loaded (OMIS_VERSION layout). */
OMIS_API int omisGetVersion(void);

/* First error on this thread since the last call, and clears it. *message (if
 * message is not NULL) stays valid until the next omis call on this thread. */
OMIS_API OMISError omisGetError(const char** message);

/* Called for every error, on the thread that raised it; NULL removes it. */
OMIS_API void omisSetErrorFunction(OMISErrorFunction function, void* user);

/* ---- MIS estimator (SPEC §1–§2) ---------------------------------------- */

typedef struct OMISEstimatorImpl* OMISEstimator;

typedef enum OMISStrategy {
    OMIS_STRATEGY_BALANCE = 0,
    OMIS_STRATEGY_POWER = 1,
    OMIS_STRATEGY_MAXIMUM = 2,
    OMIS_STRATEGY_CUTOFF = 3,
    OMIS_STRATEGY_OPTIMAL_DIRECT = 10,
    OMIS_STRATEGY_OPTIMAL_PROGRESSIVE = 11
} OMISStrategy;

/* Strategy from its interface name ("balance", "optimal-direct", ...);
 * returns false for an unknown name. */
OMIS_API bool omisParseStrategy(const char* name, OMISStrategy* strategy);

/* An estimator combining numTechniques (1..32) techniques over numChannels
 * (1..4) channels; counts[k] = samples of technique k per round (copied). */
OMIS_API OMISEstimator omisNewEstimator(OMISStrategy strategy, int numTechniques,
                                        int numChannels, const int* counts);
OMIS_API void omisRetainEstimator(OMISEstimator estimator);
OMIS_API void omisReleaseEstimator(OMISEstimator estimator);

/* Options: "beta" (power heuristic exponent, default 2), "cutoff" (cutoff
 * heuristic threshold, default 0.1). Only before commit. */
OMIS_API void omisSetEstimatorFloat(OMISEstimator estimator, const char* name, double value);
OMIS_API void omisCommitEstimator(OMISEstimator estimator);

/* Adds count samples, ordered round by round. Arrays are read during the call
 * only; strides are in bytes between consecutive samples:
 *   technique: int, which technique drew the sample
 *   pdfs:      numTechniques doubles, p_k(x) for every technique k
 *   f:         numChannels doubles, the integrand
 * Returns false (and adds nothing after the offending sample) on bad input. */
OMIS_API bool omisEstimatorAddSamples(OMISEstimator estimator, size_t count,
                                      const int* technique, size_t techniqueStride,
                                      const double* pdfs, size_t pdfStride,
                                      const double* f, size_t fStride);

/* Writes numChannels estimates and, if variance is not NULL, their estimated
 * variances. Needs at least one complete round and no partial one. */
OMIS_API bool omisEstimatorGetResult(OMISEstimator estimator, double* estimate,
                                     double* variance);

/* Forgets every sample; the settings stay. */
OMIS_API void omisResetEstimator(OMISEstimator estimator);

#endif /* OMIS_H */
