// C ABI of direct-lighting jobs (omis.h, "Scenes and direct lighting").
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "api_common.h"
#include "render/direct_lighting.h"
#include "scene_impl.h"

using namespace omis::api;

namespace {

// The parameters set by name, with the function that sets each.
enum class ParameterType { Int, Float, String };

struct ParameterName {
    const char* name;
    ParameterType type;
};

constexpr ParameterName kParameters[] = {
    {"rounds", ParameterType::Int},        {"seed", ParameterType::Int},
    {"beta", ParameterType::Float},        {"cutoff", ParameterType::Float},
    {"techniques", ParameterType::String}, {"strategy", ParameterType::String},
};

const char* type_word(ParameterType type) {
    switch (type) {
        case ParameterType::Int: return "integer";
        case ParameterType::Float: return "float";
        case ParameterType::String: return "string";
    }
    return "?";
}

const char* setter_of(ParameterType type) {
    switch (type) {
        case ParameterType::Int: return "omisSetDirectLightingInt";
        case ParameterType::Float: return "omisSetDirectLightingFloat";
        case ParameterType::String: return "omisSetDirectLightingString";
    }
    return "?";
}

// The error for a name the setter of `type` does not take: either it belongs
// to another setter, or no parameter has it.
std::invalid_argument unknown_parameter(const std::string& key, ParameterType type) {
    std::string known;
    for (const ParameterName& p : kParameters) {
        if (key == p.name)
            return std::invalid_argument("name: '" + key + "' is " +
                                         (p.type == ParameterType::Int ? "an " : "a ") +
                                         type_word(p.type) + " parameter; set it with " +
                                         setter_of(p.type));
        if (p.type == type) known += std::string(known.empty() ? "" : ", ") + p.name;
    }
    return std::invalid_argument("name: unknown " + std::string(type_word(type)) +
                                 " direct-lighting parameter '" + key + "' (" + known + ")");
}

// "balance, power, ...": every strategy's interface name, from the core.
std::string strategy_list() {
    using omis::Strategy;
    std::string list;
    for (Strategy s : {Strategy::Balance, Strategy::Power, Strategy::Maximum, Strategy::Cutoff,
                       Strategy::OptimalDirect, Strategy::OptimalProgressive})
        list += std::string(list.empty() ? "" : ", ") + omis::strategy_name(s);
    return list;
}

std::string fmt_row(const double* v) {
    return "(" + std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " +
           std::to_string(v[2]) + ")";
}

// Checks the points and normals and returns the normals normalised.
std::vector<double> unit_normals(const double* points, const double* normals,
                                 std::size_t count) {
    std::vector<double> unit(3 * count);
    for (std::size_t i = 0; i < count; ++i) {
        const double* p = points + 3 * i;
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
            throw std::invalid_argument("points: point " + std::to_string(i) +
                                        " is not finite: " + fmt_row(p));
        const double* n = normals + 3 * i;
        if (!std::isfinite(n[0]) || !std::isfinite(n[1]) || !std::isfinite(n[2]))
            throw std::invalid_argument("normals: normal " + std::to_string(i) +
                                        " is not finite: " + fmt_row(n));
        // Scale first so neither tiny nor huge components under/overflow.
        const double scale = std::max({std::abs(n[0]), std::abs(n[1]), std::abs(n[2])});
        if (!(scale > 0))
            throw std::invalid_argument("normals: normal " + std::to_string(i) +
                                        " has zero length");
        const double x = n[0] / scale, y = n[1] / scale, z = n[2] / scale;
        const double len = std::sqrt(x * x + y * y + z * z);
        unit[3 * i + 0] = x / len;
        unit[3 * i + 1] = y / len;
        unit[3 * i + 2] = z / len;
    }
    return unit;
}

OMISDirectLightingStats to_c(const omis::DirectLightingStats& r) {
    OMISDirectLightingStats out{};
    out.points = r.points;
    out.samples = r.samples;
    out.raysTraced = r.rays_traced;
    out.misSystems = r.mis_systems;
    out.pdfEvaluations = r.pdf_evaluations;
    out.seconds = r.seconds;
    return out;
}

}  // namespace

struct OMISDirectLightingImpl : Tagged<0x5448474c> {  // "LGHT"
    OMISSceneImpl* scene = nullptr;  // retained
    omis::DirectLightingSettings settings;
    std::string techniques;          // as set; resolved by commit
    std::vector<int> counts;
    bool committed = false;

    std::mutex progress_mutex;  // the progress function may be set while others execute
    OMISProgressFunction progress = nullptr;
    void* progress_user = nullptr;

    ~OMISDirectLightingImpl() override {
        if (scene) release(scene);
    }
    void require_uncommitted(const std::string& what) const {
        if (committed)
            throw ApiError(OMIS_ERROR_INVALID_OPERATION,
                           what + ": parameters cannot change after omisCommitDirectLighting");
    }
    omis::ProgressFunction progress_function() {
        std::lock_guard<std::mutex> lock(progress_mutex);
        if (!progress) return nullptr;
        const OMISProgressFunction fn = progress;
        void* user = progress_user;
        return [fn, user](double fraction) { return fn(user, fraction); };
    }
};

OMIS_API OMISDirectLighting omisNewDirectLighting(OMISScene scene) {
    return guarded<OMISDirectLighting>(nullptr, [&] {
        auto* s = checked(scene, "scene");
        auto lighting = std::make_unique<OMISDirectLightingImpl>();
        retain(s);
        lighting->scene = s;
        return lighting.release();
    });
}

OMIS_API void omisRetainDirectLighting(OMISDirectLighting lighting) {
    guarded_void([&] { retain(checked(lighting, "lighting")); });
}
OMIS_API void omisReleaseDirectLighting(OMISDirectLighting lighting) {
    guarded_void([&] { release(checked(lighting, "lighting")); });
}

OMIS_API void omisSetDirectLightingInt(OMISDirectLighting lighting, const char* name,
                                       int64_t value) {
    guarded_void([&] {
        auto* l = checked(lighting, "lighting");
        const std::string key = checked(name, "name");
        l->require_uncommitted(key);
        if (key == "rounds") {
            if (value < 1 || value > (1 << 20))
                throw std::invalid_argument("rounds: " + std::to_string(value) +
                                            " is out of range [1, 1048576]");
            l->settings.rounds = int(value);
        } else if (key == "seed") {
            l->settings.seed = std::uint64_t(value);
        } else {
            throw unknown_parameter(key, ParameterType::Int);
        }
    });
}

OMIS_API void omisSetDirectLightingFloat(OMISDirectLighting lighting, const char* name,
                                         double value) {
    guarded_void([&] {
        auto* l = checked(lighting, "lighting");
        const std::string key = checked(name, "name");
        l->require_uncommitted(key);
        auto& options = l->settings.options;
        if (key == "beta") {
            if (!(value > 0) || !std::isfinite(value))
                throw std::invalid_argument("beta: must be a positive finite number, got " +
                                            std::to_string(value));
            options.beta = value;
        } else if (key == "cutoff") {
            if (!(value >= 0 && value <= 1))
                throw std::invalid_argument("cutoff: must lie in [0, 1], got " +
                                            std::to_string(value));
            options.cutoff = value;
        } else {
            throw unknown_parameter(key, ParameterType::Float);
        }
    });
}

OMIS_API void omisSetDirectLightingString(OMISDirectLighting lighting, const char* name,
                                          const char* value) {
    guarded_void([&] {
        auto* l = checked(lighting, "lighting");
        const std::string key = checked(name, "name");
        l->require_uncommitted(key);
        const std::string v = value ? value : "";
        if (key == "techniques") {
            if (!v.empty()) parse_technique_list(v);  // names checked now, counts at commit
            l->techniques = v;
        } else if (key == "strategy") {
            const auto strategy = omis::parse_strategy(v);
            if (!strategy)
                throw std::invalid_argument("strategy: unknown strategy '" + v + "' (" +
                                            strategy_list() + ")");
            l->settings.strategy = *strategy;
        } else {
            throw unknown_parameter(key, ParameterType::String);
        }
    });
}

OMIS_API void omisSetDirectLightingCounts(OMISDirectLighting lighting, const int* counts,
                                          int numCounts) {
    guarded_void([&] {
        auto* l = checked(lighting, "lighting");
        l->require_uncommitted("counts");
        if (numCounts < 0) throw std::invalid_argument("numCounts: must not be negative");
        if (numCounts > 0) checked(counts, "counts");
        l->counts.assign(counts, counts + numCounts);
    });
}

OMIS_API void omisSetDirectLightingProgressFunction(OMISDirectLighting lighting,
                                                    OMISProgressFunction progress,
                                                    void* user) {
    guarded_void([&] {
        auto* l = checked(lighting, "lighting");
        std::lock_guard<std::mutex> lock(l->progress_mutex);
        l->progress = progress;
        l->progress_user = user;
    });
}

OMIS_API void omisCommitDirectLighting(OMISDirectLighting lighting) {
    guarded_void([&] {
        auto* l = checked(lighting, "lighting");
        if (l->committed) return;
        const omis::Scene& scene = l->scene->committed_scene("omisCommitDirectLighting");
        TechniqueChoice choice = choose_techniques(scene, l->techniques, l->counts);
        omis::DirectLightingSettings settings = l->settings;
        settings.techniques = std::move(choice.techniques);
        settings.samples = std::move(choice.samples);
        omis::LightingContext check(scene, settings);  // validates without shading
        l->settings = std::move(settings);
        l->committed = true;
    });
}

OMIS_API bool omisExecuteDirectLighting(OMISDirectLighting lighting, const double* points,
                                        const double* normals, size_t count, double* value,
                                        double* variance, OMISDirectLightingStats* stats) {
    return guarded(false, [&] {
        auto* l = checked(lighting, "lighting");
        ScopedRetain hold(l);
        if (stats) *stats = OMISDirectLightingStats{};
        if (!l->committed)
            throw ApiError(OMIS_ERROR_INVALID_OPERATION,
                           "lighting: not committed (call omisCommitDirectLighting first)");
        if (count == 0) return true;
        checked(points, "points");
        checked(normals, "normals");
        checked(value, "value");
        if (count > std::numeric_limits<std::size_t>::max() / (3 * sizeof(double)))
            throw std::invalid_argument("count: too many points");

        const std::vector<double> unit = unit_normals(points, normals, count);
        std::vector<double> scratch;
        if (!variance) {
            scratch.resize(3 * count);
            variance = scratch.data();
        }
        const omis::DirectLightingStats r =
            omis::direct_lighting(l->scene->scene, points, unit.data(), count, l->settings,
                                  value, variance, l->progress_function());
        if (stats) *stats = to_c(r);
        if (r.cancelled)
            throw ApiError(OMIS_ERROR_CANCELLED,
                           "omisExecuteDirectLighting: cancelled by the progress callback");
        return true;
    });
}
