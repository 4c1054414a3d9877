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

// A parameter's type: which of the three setters takes it.
enum ParameterType { kInt, kFloat, kString };
constexpr const char* kTypeNames[] = {"integer", "float", "string"};
constexpr const char* kSetters[] = {"omisSetDirectLightingInt", "omisSetDirectLightingFloat",
                                    "omisSetDirectLightingString"};

// A value as one of the setters received it.
struct ParameterValue {
    explicit ParameterValue(ParameterType t) : type(t) {}
    ParameterType type;
    std::int64_t integer = 0;
    double real = 0;
    std::string text;
};

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
    return {r.points, r.samples, r.rays_traced, r.mis_systems, r.pdf_evaluations, r.seconds};
}

}  // namespace

struct OMISDirectLightingImpl : Tagged<0x5448474c> {  // "LGHT"
    OMISSceneImpl* const scene;      // retained
    omis::DirectLightingSettings settings;
    std::string techniques;          // as set; resolved by commit
    std::vector<int> counts;
    bool committed = false;

    ProgressSlot progress;

    explicit OMISDirectLightingImpl(OMISSceneImpl* s) : scene(s) { retain(s); }
    ~OMISDirectLightingImpl() override { release(scene); }
    void require_uncommitted(const std::string& what) const {
        if (committed)
            throw ApiError(OMIS_ERROR_INVALID_OPERATION,
                           what + ": parameters cannot change after omisCommitDirectLighting");
    }
};

namespace {

using Lighting = OMISDirectLightingImpl;

void set_rounds(Lighting& l, const ParameterValue& v) {
    if (v.integer < 1 || v.integer > (1 << 20))
        throw std::invalid_argument("rounds: " + std::to_string(v.integer) +
                                    " is out of range [1, 1048576]");
    l.settings.rounds = int(v.integer);
}
void set_streams(Lighting& l, const ParameterValue& v) {
    if (v.integer < 1 || v.integer > omis::kMaxSampleStreams)
        throw std::invalid_argument("streams: " + std::to_string(v.integer) +
                                    " is out of range [1, " +
                                    std::to_string(omis::kMaxSampleStreams) + "]");
    l.settings.streams = int(v.integer);
}
void set_seed(Lighting& l, const ParameterValue& v) {
    l.settings.seed = std::uint64_t(v.integer);
}
void set_beta(Lighting& l, const ParameterValue& v) {
    if (!(v.real > 0) || !std::isfinite(v.real))
        throw std::invalid_argument("beta: must be a positive finite number, got " +
                                    std::to_string(v.real));
    l.settings.options.beta = v.real;
}
void set_cutoff(Lighting& l, const ParameterValue& v) {
    if (!(v.real >= 0 && v.real <= 1))
        throw std::invalid_argument("cutoff: must lie in [0, 1], got " + std::to_string(v.real));
    l.settings.options.cutoff = v.real;
}
void set_techniques(Lighting& l, const ParameterValue& v) {
    if (!v.text.empty()) parse_technique_list(v.text);  // names checked now, counts at commit
    l.techniques = v.text;
}
void set_strategy(Lighting& l, const ParameterValue& v) {
    const auto strategy = omis::parse_strategy(v.text);
    if (!strategy)
        throw std::invalid_argument("strategy: unknown strategy '" + v.text + "' (" +
                                    strategy_list() + ")");
    l.settings.strategy = *strategy;
}

// Every parameter set by name (omis.h lists them with their defaults).
struct Parameter {
    const char* name;
    ParameterType type;
    void (*set)(Lighting&, const ParameterValue&);  // validates, then stores
};
constexpr Parameter kParameters[] = {
    {"rounds", kInt, set_rounds},           {"seed", kInt, set_seed},
    {"streams", kInt, set_streams},
    {"beta", kFloat, set_beta},             {"cutoff", kFloat, set_cutoff},
    {"techniques", kString, set_techniques}, {"strategy", kString, set_strategy},
};

// What every setter does: find the parameter, check it takes this type, set it.
// Errors name an unknown parameter (with the known ones of that type) or the
// setter that takes it.
void set_parameter(OMISDirectLighting lighting, const char* name, const ParameterValue& value) {
    guarded_void([&] {
        auto* l = checked(lighting, "lighting");
        const std::string key = checked(name, "name");
        l->require_uncommitted(key);
        std::string known;
        for (const Parameter& p : kParameters) {
            if (key == p.name && p.type == value.type) return p.set(*l, value);
            if (key == p.name)
                throw std::invalid_argument("name: '" + key + "' is " +
                                            (p.type == kInt ? "an " : "a ") +
                                            kTypeNames[p.type] + " parameter; set it with " +
                                            kSetters[p.type]);
            if (p.type == value.type) known += std::string(known.empty() ? "" : ", ") + p.name;
        }
        throw std::invalid_argument("name: unknown " + std::string(kTypeNames[value.type]) +
                                    " direct-lighting parameter '" + key + "' (" + known + ")");
    });
}

}  // namespace

OMIS_API OMISDirectLighting omisNewDirectLighting(OMISScene scene) {
    return guarded<OMISDirectLighting>(
        nullptr, [&] { return new OMISDirectLightingImpl(checked(scene, "scene")); });
}

OMIS_API void omisRetainDirectLighting(OMISDirectLighting lighting) {
    retain_handle(lighting, "lighting");
}
OMIS_API void omisReleaseDirectLighting(OMISDirectLighting lighting) {
    release_handle(lighting, "lighting");
}

OMIS_API void omisSetDirectLightingInt(OMISDirectLighting lighting, const char* name,
                                       int64_t value) {
    ParameterValue v(kInt);
    v.integer = value;
    set_parameter(lighting, name, v);
}

OMIS_API void omisSetDirectLightingFloat(OMISDirectLighting lighting, const char* name,
                                         double value) {
    ParameterValue v(kFloat);
    v.real = value;
    set_parameter(lighting, name, v);
}

OMIS_API void omisSetDirectLightingString(OMISDirectLighting lighting, const char* name,
                                          const char* value) {
    ParameterValue v(kString);
    v.text = value ? value : "";
    set_parameter(lighting, name, v);
}

OMIS_API void omisSetDirectLightingCounts(OMISDirectLighting lighting, const int* counts,
                                          int numCounts) {
    guarded_void([&] {
        auto* l = checked(lighting, "lighting");
        l->require_uncommitted("counts");
        l->counts = counts_argument(counts, numCounts);
    });
}

OMIS_API void omisSetDirectLightingProgressFunction(OMISDirectLighting lighting,
                                                    OMISProgressFunction progress,
                                                    void* user) {
    guarded_void([&] { checked(lighting, "lighting")->progress.set(progress, user); });
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
                                  value, variance, l->progress.get());
        if (stats) *stats = to_c(r);
        if (r.cancelled)
            throw ApiError(OMIS_ERROR_CANCELLED,
                           "omisExecuteDirectLighting: cancelled by the progress callback");
        return true;
    });
}
