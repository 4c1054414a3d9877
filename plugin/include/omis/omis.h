/* omis — optimal multiple importance sampling for baked direct lighting.
 *
 * The stable plain-C interface to the omis library. Objects are opaque,
 * reference-counted handles: omisNewX creates one with a count of 1,
 * omisRetainX adds a reference, omisReleaseX drops one and frees the object
 * when none is left. Parameters are set, then the object is committed (once:
 * a second commit is an error), then it is used; using an uncommitted object
 * is an error.
 *
 * Handles carry a tag checked on entry: NULL, a handle of another kind, a
 * pointer to something else, or a handle whose last reference was released
 * gives OMIS_ERROR_INVALID_ARGUMENT ("not a live handle") instead of being
 * used. Detecting a released handle relies on its freed memory still reading
 * back as released, which the allocator does not promise: using a handle after
 * its last release remains undefined behaviour; the check makes it usually an
 * error. Enum arguments outside their enumeration are errors too.
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

/* Versions: while the major version is 0 the interface may still change, and
 * every change that breaks source or binary compatibility raises the minor
 * version (patch back to 0); additions raise the patch version. A program
 * checks omisGetVersion() against OMIS_VERSION at start-up to know it loaded
 * the library it was built for (the Python module does).
 *   0.2.0: omisDirectLighting's argument list became the OMISDirectLighting
 *          object (omisNewDirectLighting, omisSetDirectLighting*,
 *          omisCommitDirectLighting, omisExecuteDirectLighting).
 *   0.2.1: omisGetBakeResultWork (OMISBakeWork: draws, drawsPerTexel,
 *          shadowedTexels); OMISBakeStats.samples counts the texels' schedules.
 *   0.2.2: omisGetBakeResultBuriedTexels (texels inside other objects);
 *          omisSetWorldImage, omisSetWorldImageFile (image-based worlds);
 *          scene snapshots (omisSaveScene, omisLoadScene, ...), mesh names,
 *          tile-range bakes ("firstTile", "tileCount", omisGetBakeTileCount,
 *          omisComposeBakeResult). */
#define OMIS_VERSION_MAJOR 0
#define OMIS_VERSION_MINOR 2
#define OMIS_VERSION_PATCH 2
#define OMIS_VERSION (OMIS_VERSION_MAJOR * 10000 + OMIS_VERSION_MINOR * 100 + OMIS_VERSION_PATCH)
#define OMIS_VERSION_STRING "0.2.2"

/* Limits of every MIS system: techniques combined, channels per sample. */
#define OMIS_MAX_TECHNIQUES 32
#define OMIS_MAX_CHANNELS 4

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

/* An estimator combining numTechniques (1..OMIS_MAX_TECHNIQUES) techniques over
 * numChannels (1..OMIS_MAX_CHANNELS) channels; counts[k] = samples of technique k per round (copied). */
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
OMIS_API bool omisAddEstimatorSamples(OMISEstimator estimator, size_t count,
                                      const int* technique, size_t techniqueStride,
                                      const double* pdfs, size_t pdfStride,
                                      const double* f, size_t fStride);

/* Writes numChannels estimates and, if variance is not NULL, their estimated
 * variances. Needs at least one complete round and no partial one. */
OMIS_API bool omisGetEstimatorResult(OMISEstimator estimator, double* estimate,
                                     double* variance);

/* Forgets every sample; the settings stay. */
OMIS_API void omisResetEstimator(OMISEstimator estimator);

/* ---- Scenes and direct lighting (SPEC §3–§4) --------------------------- */

/* A scene: triangle meshes (occluders, and emitters when they carry emission)
 * plus lights in physical units (Blender 3.4 / Cycles conventions, SPEC §4).
 * Add meshes and lights, commit, then query; adding after commit and querying
 * before it are OMIS_ERROR_INVALID_OPERATION. Build a scene from one thread;
 * a committed scene is read-only and may be lit from several threads at once.
 * All positions are world space in metres, all vectors (x, y, z). */
typedef struct OMISSceneImpl* OMISScene;

/* Returned instead of a mesh or light id when a call fails. */
#define OMIS_INVALID_ID 0xFFFFFFFFu

typedef enum OMISDataType {
    OMIS_DATA_FLOAT32 = 1,
    OMIS_DATA_FLOAT64 = 2
} OMISDataType;

/* Progress of a long call: fraction done in [0, 1]. Returning false cancels
 * the call, which then fails with OMIS_ERROR_CANCELLED. May be called from any
 * thread, several threads at once, and not necessarily with increasing
 * fractions; it must be thread-safe and quick. */
typedef bool (*OMISProgressFunction)(void* user, double fraction);

OMIS_API OMISScene omisNewScene(void);
OMIS_API void omisRetainScene(OMISScene scene);
OMIS_API void omisReleaseScene(OMISScene scene);

/* Adds a triangle mesh; returns its id (0, 1, ...) or OMIS_INVALID_ID.
 * Every array is read during the call only (the scene keeps its own copy).
 *   vertices:      numVertices rows of 3 scalars of `type`, vertexByteStride
 *                  bytes apart (0 = tightly packed)
 *   triangles:     numTriangles rows of 3 vertex indices, tightly packed;
 *                  counter-clockwise seen from the front
 *   cornerNormals: NULL, or 3·numTriangles rows of 3 scalars of `type`,
 *                  tightly packed: shading normals per triangle corner
 *   cornerUVs:     NULL, or 3·numTriangles rows of 2 scalars of `type`
 *   emission:      NULL, or RGB radiance W/(m² sr): the mesh then also emits
 *                  (two-sided, one triangle light per triangle) */
OMIS_API unsigned int omisAddMesh(OMISScene scene, const void* vertices, OMISDataType type,
                                       size_t vertexByteStride, size_t numVertices,
                                       const uint32_t* triangles, size_t numTriangles,
                                       const void* cornerNormals, const void* cornerUVs,
                                       const float* emission);

/* Lights; each returns the light id or OMIS_INVALID_ID. RGB triples are
 * radiance W/(m² sr) for area lights and the world, intensity W/sr for point
 * and spot lights, irradiance W/m² for the sun. Angles are in radians.
 * `spread` is Blender's area-light spread (π: no effect). */

/* Rectangle corner + [0,1]·edgeU + [0,1]·edgeV (perpendicular edges);
 * one-sided lights emit toward cross(edgeU, edgeV). */
OMIS_API unsigned int omisAddRectLight(OMISScene scene, const double corner[3],
                                            const double edgeU[3], const double edgeV[3],
                                            const double radiance[3], bool twoSided,
                                            double spread);
/* Ellipse (or disk) center + a·axisA + b·axisB, a² + b² ≤ 1, perpendicular
 * semi-axes; one-sided lights emit toward cross(axisA, axisB). */
OMIS_API unsigned int omisAddEllipseLight(OMISScene scene, const double center[3],
                                               const double axisA[3], const double axisB[3],
                                               const double radiance[3], bool twoSided,
                                               double spread);
/* radius 0: a delta light (one shadow ray); radius > 0: a disk facing the
 * receiver of radiance intensity/(π radius²). */
OMIS_API unsigned int omisAddPointLight(OMISScene scene, const double position[3],
                                             const double intensity[3], double radius);
/* spotSize: full cone angle; spotBlend in [0, 1] (Blender's smoothstep). */
OMIS_API unsigned int omisAddSpotLight(OMISScene scene, const double position[3],
                                            const double direction[3],
                                            const double intensity[3], double radius,
                                            double spotSize, double spotBlend);
/* direction: the way the light travels; angle: full angular diameter (0 =
 * delta light). */
OMIS_API unsigned int omisAddSunLight(OMISScene scene, const double direction[3],
                                           const double irradiance[3], double angle);
/* Constant radiance from every direction; a second call replaces the first. */
OMIS_API unsigned int omisSetWorld(OMISScene scene, const double radiance[3]);
/* An image-based world (replaces an earlier world): an equirectangular RGB
 * radiance map in Cycles' convention — u = 0.5 − atan2(y, x)/(2π),
 * v = 1 − acos(z)/π: the image's centre looks along +X, u grows toward −Y,
 * row 0 is the top row (the zenith, +Z). `rgb`: height rows of width × 3
 * floats, row r starting rowByteStride·r bytes after rgb (0: packed), copied
 * before the call returns. `rotation`: Euler XYZ in radians as Blender's
 * Mapping node (the map is looked up at Rz·Ry·Rx·ω; NULL: none).
 * `compensate`: draw from max(0, map − mean) (MIS compensation, Karlík et
 * al. 2019) instead of the map. NaN, infinite or negative texels, a
 * non-finite rotation or a size of 0 give OMIS_ERROR_INVALID_ARGUMENT. */
OMIS_API unsigned int omisSetWorldImage(OMISScene scene, const float* rgb, size_t width,
                                        size_t height, size_t rowByteStride,
                                        const double rotation[3], bool compensate);
/* The same from an image file read with OpenImageIO (EXR, Radiance HDR, ...;
 * grey images are spread to RGB, alpha is dropped). A file that cannot be
 * read gives OMIS_ERROR_INVALID_ARGUMENT naming the path. */
OMIS_API unsigned int omisSetWorldImageFile(OMISScene scene, const char* path,
                                            const double rotation[3], bool compensate);
/* Blender's cycles.cast_shadow and cycles.use_multiple_importance_sampling
 * (false: the `bsdf` technique does not see the light). Before commit only. */
OMIS_API void omisSetLightFlags(OMISScene scene, unsigned int light, bool castShadow,
                                     bool visibleToBsdf);
/* Whether commit draws a compact emissive mesh (at least 64 triangles whose
 * area is at least 3/4 of their bounding sphere's: a sphere-like body) as one
 * light, toward its bounding sphere, instead of a light per triangle; on by
 * default. Off gives the per-triangle light tree. Before commit only. */
OMIS_API void omisSetMeshLights(OMISScene scene, bool enabled);

/* The diffuse closure of a mesh's surface when it is baked, evaluated as
 * Cycles 3.4's Diffuse bake does (viewed along the normal, divided by the
 * closure's colour; SPEC §3). Default: Lambert. */
typedef enum OMISReceiver {
    OMIS_RECEIVER_LAMBERT = 0,             /* cosθ/π; roughness ignored */
    OMIS_RECEIVER_PRINCIPLED_DIFFUSE = 1,  /* Principled BSDF's diffuse, its Roughness (≥ 0) */
    OMIS_RECEIVER_OREN_NAYAR = 2           /* Diffuse BSDF, its Roughness (σ, clamped to [0, 1]) */
} OMISReceiver;

/* Sets mesh's receiver closure; before commit only. roughness must be finite
 * and ≥ 0 (OMIS_ERROR_INVALID_ARGUMENT otherwise, as for an unknown mesh id). */
OMIS_API void omisSetMeshReceiver(OMISScene scene, unsigned int mesh, OMISReceiver receiver,
                                  double roughness);

/* Builds the acceleration structure and the emissive-mesh lights. A second
 * commit does nothing. */
OMIS_API void omisCommitScene(OMISScene scene);

/* ---- Scene snapshots and mesh names ------------------------------------- */

/* A snapshot is a file of everything a bake reads from a scene (meshes and
 * their names, UVs, normals, emission and receivers; lights and their flags;
 * the world; scene options), versioned and checksummed: a scene loaded from
 * it is committed and bakes the same bits as the scene saved. Saving works
 * before or after commit; the file is written atomically (temporary file,
 * then rename). Returns false on error. */
OMIS_API bool omisSaveScene(OMISScene scene, const char* path);
/* The snapshot as bytes: writes it to buffer when bufferSize is large enough
 * and returns its size either way (0 on error), so a call with bufferSize 0
 * queries the size. */
OMIS_API size_t omisSaveSceneToMemory(OMISScene scene, void* buffer, size_t bufferSize);
/* A new committed scene (count 1) from a snapshot file or bytes; NULL on
 * error. A truncated or corrupted file (checksums), another format version or
 * counts that do not fit the file give OMIS_ERROR_INVALID_ARGUMENT with a
 * message naming the problem. The bytes are read during the call only. */
OMIS_API OMISScene omisLoadScene(const char* path);
OMIS_API OMISScene omisLoadSceneFromMemory(const void* data, size_t size);
/* Names a mesh (any time; names appear in errors and snapshots). */
OMIS_API void omisSetMeshName(OMISScene scene, unsigned int mesh, const char* name);
/* The first mesh of that name, or OMIS_INVALID_ID (an error) when none is. */
OMIS_API unsigned int omisFindMesh(OMISScene scene, const char* name);
/* A mesh's name, written and sized as omisGetEffectPlan. */
OMIS_API size_t omisGetMeshName(OMISScene scene, unsigned int mesh, char* buffer,
                                size_t bufferSize);
/* How many meshes the scene holds (OMIS_INVALID_ID on error). */
OMIS_API unsigned int omisGetMeshCount(OMISScene scene);

/* Techniques (SPEC §3) are named in one comma-separated string, for example
 * "bsdf,unoccluded/solid-angle"; `samples` then holds one count per name
 * (samples per round, >= 0). NULL or "" chooses the effect plan's default
 * techniques and sample counts for the scene, and samples is ignored. */

/* The effect plan of a committed scene for these techniques, as text. Writes
 * at most bufferSize bytes including a terminating NUL (buffer may be NULL
 * when bufferSize is 0) and returns the full length without the NUL, so a
 * call with bufferSize 0 queries the size. Returns 0 on error. */
OMIS_API size_t omisGetEffectPlan(OMISScene scene, const char* techniques, const int* samples,
                                  char* buffer, size_t bufferSize);

/* Every technique name the ABI accepts (SPEC §3), comma-separated, "bsdf"
 * first; written and sized as omisGetEffectPlan. */
OMIS_API size_t omisGetTechniqueNames(char* buffer, size_t bufferSize);

/* A direct-lighting job on a committed scene: set parameters by name, commit,
 * then execute (any number of times, from several threads at once; the
 * parameters are read-only after commit). */
typedef struct OMISDirectLightingImpl* OMISDirectLighting;

/* What one execution did. */
typedef struct OMISDirectLightingStats {
    uint64_t points;
    uint64_t samples;        /* directions drawn */
    uint64_t raysTraced;     /* shadow and BSDF rays */
    uint64_t misSystems;     /* per-point MIS estimators built */
    uint64_t pdfEvaluations; /* light-technique pdf evaluations */
    double seconds;          /* wall-clock time */
} OMISDirectLightingStats;

/* The job keeps a reference to the scene, which need not be committed yet. */
OMIS_API OMISDirectLighting omisNewDirectLighting(OMISScene scene);
OMIS_API void omisRetainDirectLighting(OMISDirectLighting lighting);
OMIS_API void omisReleaseDirectLighting(OMISDirectLighting lighting);

/* Parameters, before commit (defaults in brackets). An unknown name, a name
 * set through the wrong type's function, or a bad value is
 * OMIS_ERROR_INVALID_ARGUMENT naming the parameter:
 *   integers: "rounds" [1] R (SPEC §1), 1..2^20; "seed" [0] (the 64 bits as
 *             uint64): results are a function of the seed only, not of the
 *             number of threads; "streams" [1] independently randomized
 *             streams per point, 1..4: 1 = one scrambled sequence (least
 *             error; the variance output is then the independent-draw
 *             formula, an upper estimate), more = the variance output is the
 *             streams' measured spread, at some cost in error
 *   floats:   "beta" [2] power heuristic exponent, > 0; "cutoff" [0.1] cutoff
 *             heuristic threshold, in [0, 1]
 *   strings:  "techniques" [""] comma-separated names (SPEC §3), for example
 *             "bsdf,unoccluded/solid-angle"; "" = the effect plan's default
 *             techniques and counts; "strategy" ["optimal-direct"] the MIS
 *             combination by name (omisParseStrategy's names)
 *   counts:   samples of each named technique per round [1 each], >= 0, one
 *             per name; only with techniques */
OMIS_API void omisSetDirectLightingInt(OMISDirectLighting lighting, const char* name,
                                       int64_t value);
OMIS_API void omisSetDirectLightingFloat(OMISDirectLighting lighting, const char* name,
                                         double value);
OMIS_API void omisSetDirectLightingString(OMISDirectLighting lighting, const char* name,
                                          const char* value);
OMIS_API void omisSetDirectLightingCounts(OMISDirectLighting lighting, const int* counts,
                                          int numCounts);
/* Called now and then with the fraction done (any thread, see
 * OMISProgressFunction); returning false cancels the execution. May be set at
 * any time; an execution uses the function set when it starts. */
OMIS_API void omisSetDirectLightingProgressFunction(OMISDirectLighting lighting,
                                                    OMISProgressFunction progress,
                                                    void* user);
/* Validates the parameters against the (committed) scene and chooses the
 * techniques; errors name the parameter. A second commit does nothing. */
OMIS_API void omisCommitDirectLighting(OMISDirectLighting lighting);

/* E_direct/π per RGB channel at `count` shading points (SPEC §3): what Cycles'
 * Diffuse bake with only Direct writes.
 *   points, normals: count rows of 3 doubles, tightly packed; normals face the
 *                    side that receives light (normalised here; not zero)
 *   value:           count rows of 3 doubles written: the estimates
 *   variance:        NULL, or count rows of 3 doubles written: their
 *                    estimated variances
 *   stats:           NULL, or filled in (also when cancelled)
 * Arrays are read/written during the call only. count 0 does nothing and
 * succeeds. Returns false on error or cancellation (OMIS_ERROR_CANCELLED;
 * outputs then incomplete). */
OMIS_API bool omisExecuteDirectLighting(OMISDirectLighting lighting, const double* points,
                                        const double* normals, size_t count, double* value,
                                        double* variance, OMISDirectLightingStats* stats);

/* ---- Baking (lightmaps and vertex colours) ----------------------------- */

/* A bake job on one mesh of a committed scene: set parameters, commit, then
 * execute (any number of times; each execution returns a new result). */
typedef struct OMISBakeImpl* OMISBake;
/* The outcome of one execution: images (or per-vertex arrays) and statistics. */
typedef struct OMISBakeResultImpl* OMISBakeResult;

typedef enum OMISBakeTarget {
    OMIS_BAKE_LIGHTMAP = 0, /* the mesh's UV layout, width × height texels */
    OMIS_BAKE_VERTICES = 1, /* one value per mesh vertex (Blender POINT) */
    OMIS_BAKE_CORNERS = 2   /* one value per triangle corner (Blender CORNER) */
} OMISBakeTarget;

/* The job keeps a reference to the scene. */
OMIS_API OMISBake omisNewBake(OMISScene scene, OMISBakeTarget target, unsigned int mesh);
OMIS_API void omisRetainBake(OMISBake bake);
OMIS_API void omisReleaseBake(OMISBake bake);

/* Parameters, before commit (defaults in brackets):
 *   integers: "width", "height" (lightmap size, required for lightmaps),
 *             "margin" [16] texels of extension around UV islands,
 *             "samples" [64] sample budget: directions per texel in all,
 *             "seed" [0], "smoothNormals" [1], "roundsPerPass" [4] (passes are
 *             used when a time or noise budget is set), "threads" [0 = all
 *             cores; results do not depend on it]; lightmaps: "firstTile" [0]
 *             and "tileCount" [0 = all]: bake only these tiles of
 *             omisGetBakeTileCount's (16×16 texels each, row-major from the
 *             bottom left): their texels get the bits a whole bake gives them,
 *             the rest stay 0 with mask 0, and the margin is left unfilled
 *             (omisComposeBakeResult fills it once the ranges are together)
 *   floats:   "timeBudget" [0 = none] seconds, "noiseTarget" [0 = none]
 *             relative standard error per texel, "beta" [2], "cutoff" [0.1]
 *   strings:  "techniques" [""] comma-separated names (SPEC §3), "" = the
 *             effect plan's default; "strategy" ["optimal-direct"];
 *             "marginType" ["extend"] or "adjacent-faces" (Blender's margin
 *             types: extend the island's border texels, or take the texels
 *             across UV seams from the adjacent faces)
 *   counts:   samples of each named technique per round [1 each]
 * A bake stops at the first budget reached: samples, time or noise. */
OMIS_API void omisSetBakeInt(OMISBake bake, const char* name, int64_t value);
OMIS_API void omisSetBakeFloat(OMISBake bake, const char* name, double value);
OMIS_API void omisSetBakeString(OMISBake bake, const char* name, const char* value);
OMIS_API void omisSetBakeCounts(OMISBake bake, const int* counts, int numCounts);
/* Called now and then with the fraction done (any thread, see
 * OMISProgressFunction); returning false cancels the execution. */
OMIS_API void omisSetBakeProgressFunction(OMISBake bake, OMISProgressFunction progress,
                                          void* user);
/* Validates the parameters against the scene; errors name the parameter. */
OMIS_API void omisCommitBake(OMISBake bake);
/* Runs the bake; returns a new result (count 1), or NULL on error or when
 * cancelled (OMIS_ERROR_CANCELLED). Nothing is written anywhere. */
OMIS_API OMISBakeResult omisExecuteBake(OMISBake bake);
/* How many tiles a committed lightmap bake has (0 on error). */
OMIS_API size_t omisGetBakeTileCount(OMISBake bake);
/* A result put together from tile-range bakes of this (committed, lightmap)
 * bake: value (width·height·3 floats), noise and mask (width·height floats
 * each), every texel taken from the range that baked it; the margin is
 * filled as a whole bake fills it. The arrays are read during the call only.
 * Its statistics hold texels and covered only. */
OMIS_API OMISBakeResult omisComposeBakeResult(OMISBake bake, const float* value,
                                              const float* noise, const float* mask);

OMIS_API void omisRetainBakeResult(OMISBakeResult result);
OMIS_API void omisReleaseBakeResult(OMISBakeResult result);

/* Lightmaps: width × height; vertex bakes: count × 1. */
OMIS_API bool omisGetBakeResultSize(OMISBakeResult result, int* width, int* height);
/* The result's own arrays, valid while the result lives, row 0 at the bottom:
 *   "value": width·height·3 floats, E_direct/π (RGB)
 *   "noise": width·height floats, estimated relative standard error
 *   "mask":  width·height floats, 1 where baked, 0 in the margin or empty */
OMIS_API const float* omisGetBakeResultData(OMISBakeResult result, const char* name);

/* Why a bake stopped (a cancelled bake returns no result). */
typedef enum OMISBakeStatus {
    OMIS_BAKE_COMPLETE = 0,     /* the sample budget was spent */
    OMIS_BAKE_TIME_BUDGET = 1,  /* the time budget was reached (on a whole pass) */
    OMIS_BAKE_NOISE_TARGET = 2  /* every texel met the noise target */
} OMISBakeStatus;

typedef struct OMISBakeStats {
    OMISBakeStatus status;
    double seconds;
    uint64_t samples;        /* the texels' schedules: samplesPerTexel · covered */
    uint64_t raysTraced;
    double samplesPerTexel;  /* mean over baked texels */
    double meanRelativeError;
    double maxRelativeError;
    int passes;
    uint64_t texels;         /* width · height */
    uint64_t covered;        /* texels inside the UV layout */
    uint64_t degenerateUvTriangles;
} OMISBakeStats;
OMIS_API bool omisGetBakeResultStats(OMISBakeResult result, OMISBakeStats* stats);
/* The work behind the samples (0.2.1; OMISBakeStats keeps its layout): every
 * texel takes its schedule's samples, and one whose centre sees no light's
 * middle point draws 4× each technique's count in every round (the effect
 * plan's choice among several comparable lights). raysTraced counts every
 * ray, those texels' extra ones and the probe's included. */
typedef struct OMISBakeWork {
    uint64_t draws;          /* directions drawn, all techniques, extra draws included */
    double drawsPerTexel;    /* mean over baked texels */
    uint64_t shadowedTexels; /* texels drawing the extra draws */
} OMISBakeWork;
OMIS_API bool omisGetBakeResultWork(OMISBakeResult result, OMISBakeWork* work);
/* Baked texels (corners, in vertex bakes) whose centre lies inside other
 * geometry (rays from it meet the back of a surface first) or on a face of
 * another mesh turned its way (coinciding surfaces). They bake dark, as in
 * Cycles; an artist usually wants to know (overlapping props). 0.2.2; 0 on
 * error (omisGetError). */
OMIS_API uint64_t omisGetBakeResultBuriedTexels(OMISBakeResult result);

/* The bake's convergence: one record per completed pass. Passes are taken when
 * a time or noise budget is set ("timeBudget", "noiseTarget"); a bake with a
 * sample budget alone runs one pass. */
typedef struct OMISBakePass {
    double samplesPerTexel;   /* mean over baked texels, so far */
    double seconds;           /* sampling time from the first pass's start */
    double meanRelativeError; /* the running estimate's, mean over baked texels
                                 (vertex bakes: over corners) */
} OMISBakePass;
/* Writes at most capacity records (passes may be NULL when capacity is 0);
 * returns how many the result holds, or -1 on error. */
OMIS_API int omisGetBakeResultConvergence(OMISBakeResult result, OMISBakePass* passes,
                                          int capacity);
/* What halving the mean error would cost, from error ∝ t^(-beta) fitted (least
 * squares in log-log) over the last passes (at most 4; the first only when
 * there are 2), t the sampling time: seconds = t·(2^(1/beta) − 1) more. With a
 * single pass, passes too close (< 1.25× apart in time or < 1.5× in samples) or
 * an error that does not fall, beta = 0.5 is assumed — independent draws, which
 * omis' low-discrepancy draws converge at least as fast as: then seconds is an
 * upper bound and passesFitted is 0. A fitted beta is kept within [0.25, 1.5]. */
typedef struct OMISBakeHalving {
    double seconds;   /* more sampling time to halve the mean relative error */
    double beta;      /* the convergence exponent used */
    int passesFitted; /* passes behind beta; >= 2: measured, 0: assumed */
} OMISBakeHalving;
OMIS_API bool omisGetBakeResultHalving(OMISBakeResult result, OMISBakeHalving* halving);
/* The same prediction from a history of numPasses records (in pass order). */
OMIS_API bool omisPredictBakeHalving(const OMISBakePass* passes, int numPasses,
                                     OMISBakeHalving* halving);
/* The effect plan and technique choice of the bake as text; returns the full
 * length without the NUL and writes at most bufferSize bytes (as
 * omisGetEffectPlan). */
OMIS_API size_t omisGetBakeResultPlan(OMISBakeResult result, char* buffer, size_t bufferSize);

/* Files, written atomically (temporary file, then rename): a failed write
 * leaves an existing file as it was. EXR: linear float channels R, G, B,
 * noise, mask. PNG: 8-bit through the OCIO view transform of Blender's config
 * (view "Standard" or "Filmic", display "sRGB"; NULL = those defaults). */
OMIS_API bool omisWriteBakeResultEXR(OMISBakeResult result, const char* path);
OMIS_API bool omisWriteBakeResultPNG(OMISBakeResult result, const char* path,
                                     const char* view, const char* display, double exposure);

#endif /* OMIS_H */
