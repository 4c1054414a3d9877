// The scene handle, shared by the scene and bake parts of the C ABI.
#pragma once

#include <atomic>
#include <mutex>
#include <string>
#include <vector>

#include "api_common.h"
#include "render/scene.h"
#include "render/techniques.h"

struct OMISSceneImpl : omis::api::Tagged<0x4e454353> {  // "SCEN"
    omis::Scene scene;
    std::mutex build_mutex;              // serialises adds and commit
    std::atomic<bool> committed{false};  // set once commit has finished

    // Adds run under the lock, and only before commit.
    std::unique_lock<std::mutex> lock_for_build(const char* what) {
        std::unique_lock<std::mutex> lock(build_mutex);
        if (committed.load())
            throw omis::api::ApiError(OMIS_ERROR_INVALID_OPERATION,
                           std::string(what) +
                               ": the scene is already committed (add meshes "
                               "and lights before omisCommitScene)");
        return lock;
    }
    const omis::Scene& committed_scene(const char* what) const {
        if (!committed.load())
            throw omis::api::ApiError(
                OMIS_ERROR_INVALID_OPERATION,
                std::string(what) + ": scene not committed (call omisCommitScene first)");
        return scene;
    }
};

namespace omis::api {

// Holds a reference for the duration of a call, so a concurrent release by
// another thread cannot free the scene under it.
struct ScopedRetain {
    RefCounted* object;
    explicit ScopedRetain(RefCounted* o) : object(o) { retain(o); }
    ~ScopedRetain() { release(object); }
    ScopedRetain(const ScopedRetain&) = delete;
    ScopedRetain& operator=(const ScopedRetain&) = delete;
};

struct TechniqueChoice {
    std::vector<omis::Technique> techniques;
    std::vector<int> samples;
};

// The techniques of a comma-separated list (spaces around names ignored);
// errors name "techniques".
std::vector<omis::Technique> parse_technique_list(const std::string& list);

// A comma-separated technique list with one sample count per name in
// `samples`, or the scene's default (effect plan) when names is NULL or "".
TechniqueChoice choose_techniques(const omis::Scene& scene, const char* names,
                                  const int* samples);

// As set on a job object: the listed techniques with `counts` per round (1 each
// when counts is empty), or the scene's default when names is empty (counts
// must then be empty too). Errors name "techniques" or "counts".
TechniqueChoice choose_techniques(const omis::Scene& scene, const std::string& names,
                                  const std::vector<int>& counts);

}  // namespace omis::api
