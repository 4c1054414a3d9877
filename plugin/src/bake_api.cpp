// C ABI of bake jobs and their results (omis.h, "Baking").
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "api_common.h"
#include "bake/bake.h"
#include "io/image_io.h"
#include "scene_impl.h"

using namespace omis::api;

struct OMISBakeImpl : Tagged<0x454b4142> {  // "BAKE"
    OMISSceneImpl* scene = nullptr;  // retained
    omis::BakeSettings settings;
    std::string techniques, strategy = "optimal-direct";
    std::vector<int> counts;
    std::int64_t samples = 64;
    OMISProgressFunction progress = nullptr;
    void* progress_user = nullptr;
    bool committed = false;

    ~OMISBakeImpl() override {
        if (scene) release(scene);
    }
    void require_uncommitted(const char* what) const {
        if (committed)
            throw ApiError(OMIS_ERROR_INVALID_OPERATION,
                           std::string(what) + ": parameters cannot change after omisCommitBake");
    }
};

struct OMISBakeResultImpl : Tagged<0x54534552> {  // "REST"
    omis::BakeResult result;
};

namespace {

int to_int(std::int64_t value, const char* name, std::int64_t lo, std::int64_t hi) {
    if (value < lo || value > hi)
        throw std::invalid_argument(std::string(name) + ": " + std::to_string(value) +
                                    " is out of range [" + std::to_string(lo) + ", " +
                                    std::to_string(hi) + "]");
    return int(value);
}

}  // namespace

OMIS_API OMISBake omisNewBake(OMISScene scene, OMISBakeTarget target, unsigned int mesh) {
    return guarded<OMISBake>(nullptr, [&] {
        auto* s = checked(scene, "scene");
        const int t = enum_value(target);
        if (t != OMIS_BAKE_LIGHTMAP && t != OMIS_BAKE_VERTICES && t != OMIS_BAKE_CORNERS)
            throw std::invalid_argument("target: unknown bake target " + std::to_string(t));
        auto bake = std::make_unique<OMISBakeImpl>();
        bake->settings.target = target == OMIS_BAKE_LIGHTMAP   ? omis::BakeTarget::Lightmap
                                : target == OMIS_BAKE_VERTICES ? omis::BakeTarget::Vertices
                                                               : omis::BakeTarget::Corners;
        bake->settings.mesh = mesh;
        retain(s);
        bake->scene = s;
        return bake.release();
    });
}

OMIS_API void omisRetainBake(OMISBake bake) {
    guarded_void([&] { retain(checked(bake, "bake")); });
}
OMIS_API void omisReleaseBake(OMISBake bake) {
    guarded_void([&] { release(checked(bake, "bake")); });
}

OMIS_API void omisSetBakeInt(OMISBake bake, const char* name, int64_t value) {
    guarded_void([&] {
        auto* b = checked(bake, "bake");
        const std::string key = checked(name, "name");
        b->require_uncommitted(key.c_str());
        auto& s = b->settings;
        if (key == "width") s.width = to_int(value, "width", 1, 1 << 16);
        else if (key == "height") s.height = to_int(value, "height", 1, 1 << 16);
        else if (key == "margin") s.margin = to_int(value, "margin", 0, 1 << 16);
        else if (key == "samples") b->samples = to_int(value, "samples", 1, 1 << 30);
        else if (key == "seed") s.lighting.seed = std::uint64_t(value);
        else if (key == "smoothNormals") s.smooth_normals = value != 0;
        else if (key == "threads") s.threads = to_int(value, "threads", 0, 1 << 16);
        else if (key == "roundsPerPass") s.rounds_per_pass = to_int(value, "roundsPerPass", 1, 1 << 20);
        else if (key == "firstTile") s.first_tile = std::size_t(to_int(value, "firstTile", 0, 1 << 30));
        else if (key == "tileCount") s.tile_count = std::size_t(to_int(value, "tileCount", 0, 1 << 30));
        else throw std::invalid_argument("name: unknown integer bake parameter '" + key + "'");
    });
}

OMIS_API void omisSetBakeFloat(OMISBake bake, const char* name, double value) {
    guarded_void([&] {
        auto* b = checked(bake, "bake");
        const std::string key = checked(name, "name");
        b->require_uncommitted(key.c_str());
        if (!std::isfinite(value)) throw std::invalid_argument(key + ": must be finite");
        auto& s = b->settings;
        if (key == "timeBudget") s.time_budget = value;
        else if (key == "noiseTarget") s.noise_target = value;
        else if (key == "beta") s.lighting.options.beta = value;
        else if (key == "cutoff") s.lighting.options.cutoff = value;
        else throw std::invalid_argument("name: unknown float bake parameter '" + key + "'");
    });
}

OMIS_API void omisSetBakeString(OMISBake bake, const char* name, const char* value) {
    guarded_void([&] {
        auto* b = checked(bake, "bake");
        const std::string key = checked(name, "name");
        b->require_uncommitted(key.c_str());
        const std::string v = value ? value : "";
        if (key == "techniques") b->techniques = v;
        else if (key == "strategy") b->strategy = v;
        else if (key == "marginType") {
            if (v == "extend") b->settings.margin_type = omis::MarginType::Extend;
            else if (v == "adjacent-faces") b->settings.margin_type = omis::MarginType::AdjacentFaces;
            else throw std::invalid_argument("marginType: expected 'extend' or 'adjacent-faces', "
                                             "got '" + v + "'");
        }
        else throw std::invalid_argument("name: unknown string bake parameter '" + key + "'");
    });
}

OMIS_API void omisSetBakeCounts(OMISBake bake, const int* counts, int numCounts) {
    guarded_void([&] {
        auto* b = checked(bake, "bake");
        b->require_uncommitted("counts");
        if (numCounts < 0) throw std::invalid_argument("numCounts: must not be negative");
        if (numCounts > 0) checked(counts, "counts");
        b->counts.assign(counts, counts + numCounts);
    });
}

OMIS_API void omisSetBakeProgressFunction(OMISBake bake, OMISProgressFunction progress,
                                          void* user) {
    guarded_void([&] {
        auto* b = checked(bake, "bake");
        b->progress = progress;
        b->progress_user = user;
    });
}

OMIS_API void omisCommitBake(OMISBake bake) {
    guarded_void([&] {
        auto* b = checked(bake, "bake");
        if (b->committed) return;
        const omis::Scene& scene = b->scene->committed_scene("bake");
        auto& s = b->settings;
        const auto strategy = omis::parse_strategy(b->strategy);
        if (!strategy)
            throw std::invalid_argument("strategy: unknown strategy '" + b->strategy + "'");
        s.lighting.strategy = *strategy;
        // Checked here, not first when the bake runs.
        const auto& o = s.lighting.options;
        if (!(o.beta > 0)) throw std::invalid_argument("beta: must be positive");
        if (!(o.cutoff >= 0 && o.cutoff <= 1)) throw std::invalid_argument("cutoff: must lie in [0, 1]");
        if (!(s.time_budget >= 0))
            throw std::invalid_argument("timeBudget: must be ≥ 0 seconds (0 = none)");
        if (!(s.noise_target >= 0))
            throw std::invalid_argument("noiseTarget: must be ≥ 0 (0 = none)");
        if (b->techniques.empty()) {
            omis::default_techniques(scene, s.lighting.techniques, s.lighting.samples,
                                     &s.lighting.shadowed_draws);
            if (!b->counts.empty())
                throw std::invalid_argument("counts: given without techniques");
        } else {
            // Parse once with placeholder counts to learn how many names there are.
            const std::vector<int> ones(1 + std::count(b->techniques.begin(),
                                                       b->techniques.end(), ','), 1);
            const TechniqueChoice probe =
                choose_techniques(scene, b->techniques.c_str(), ones.data());
            std::vector<int> counts = b->counts;
            if (counts.empty()) counts.assign(probe.techniques.size(), 1);
            if (counts.size() != probe.techniques.size())
                throw std::invalid_argument("counts: expected " +
                                            std::to_string(probe.techniques.size()) +
                                            " entries (one per technique), got " +
                                            std::to_string(counts.size()));
            const TechniqueChoice choice =
                choose_techniques(scene, b->techniques.c_str(), counts.data());
            s.lighting.techniques = choice.techniques;
            s.lighting.samples = choice.samples;
        }
        long long per_round = 0;
        for (int c : s.lighting.samples) per_round += c;
        if (per_round <= 0 && !s.lighting.techniques.empty())
            throw std::invalid_argument("counts: at least one technique needs samples");
        s.lighting.rounds = int(std::max<long long>(1, per_round ? b->samples / per_round : 1));
        s.samples = b->samples;  // exactly this many per texel (omis::BakeSettings::samples)
        if (s.target == omis::BakeTarget::Lightmap && (s.width < 1 || s.height < 1))
            throw std::invalid_argument("width, height: a lightmap bake needs both");
        // Validates the rest (mesh id, UVs, technique list) without shading.
        omis::LightingContext check(scene, s.lighting);
        if (s.mesh >= scene.geometry().num_meshes())
            throw std::invalid_argument("mesh: id " + std::to_string(s.mesh) +
                                        " is out of range (" +
                                        std::to_string(scene.geometry().num_meshes()) +
                                        " meshes)");
        if (s.target == omis::BakeTarget::Lightmap && !scene.geometry().mesh(s.mesh).has_uvs())
            throw std::invalid_argument("mesh: '" + scene.geometry().mesh(s.mesh).name +
                                        "' has no UV map to bake into");
        if (s.first_tile > 0 || s.tile_count > 0) {
            if (s.target != omis::BakeTarget::Lightmap)
                throw std::invalid_argument("firstTile, tileCount: tile ranges are for lightmaps only");
            const std::size_t tiles = omis::bake_tile_count(s.width, s.height);
            if (s.first_tile >= tiles || s.tile_count > tiles - s.first_tile)
                throw std::invalid_argument("firstTile, tileCount: the range is outside the " +
                                            std::to_string(tiles) + " tiles of the lightmap");
        }
        b->committed = true;
    });
}

OMIS_API OMISBakeResult omisExecuteBake(OMISBake bake) {
    return guarded<OMISBakeResult>(nullptr, [&] {
        auto* b = checked(bake, "bake");
        if (!b->committed)
            throw ApiError(OMIS_ERROR_INVALID_OPERATION,
                           "bake: not committed (call omisCommitBake first)");
        ScopedRetain hold(b);
        omis::BakeProgress progress;
        if (b->progress) {
            const OMISProgressFunction fn = b->progress;
            void* user = b->progress_user;
            progress = [fn, user](double fraction) { return fn(user, fraction); };
        }
        auto result = std::make_unique<OMISBakeResultImpl>();
        result->result = omis::bake(b->scene->scene, b->settings, progress);
        if (result->result.stats.status == omis::BakeStatus::Cancelled)
            throw ApiError(OMIS_ERROR_CANCELLED, "bake: cancelled");
        return result.release();
    });
}

OMIS_API void omisRetainBakeResult(OMISBakeResult result) {
    guarded_void([&] { retain(checked(result, "result")); });
}
OMIS_API void omisReleaseBakeResult(OMISBakeResult result) {
    guarded_void([&] { release(checked(result, "result")); });
}

OMIS_API bool omisGetBakeResultSize(OMISBakeResult result, int* width, int* height) {
    return guarded(false, [&] {
        const auto& r = checked(result, "result")->result;
        *checked(width, "width") = r.width;
        *checked(height, "height") = r.height;
        return true;
    });
}

OMIS_API const float* omisGetBakeResultData(OMISBakeResult result, const char* name) {
    return guarded<const float*>(nullptr, [&]() -> const float* {
        const auto& r = checked(result, "result")->result;
        const std::string key = checked(name, "name");
        if (key == "value") return r.value.data();
        if (key == "noise") return r.noise.data();
        if (key == "mask") return r.mask.data();
        throw std::invalid_argument("name: unknown result array '" + key +
                                    "' (value, noise, mask)");
    });
}

OMIS_API bool omisGetBakeResultStats(OMISBakeResult result, OMISBakeStats* stats) {
    return guarded(false, [&] {
        const auto& s = checked(result, "result")->result.stats;
        OMISBakeStats& out = *checked(stats, "stats");
        out.status = s.status == omis::BakeStatus::TimeBudget    ? OMIS_BAKE_TIME_BUDGET
                     : s.status == omis::BakeStatus::NoiseTarget ? OMIS_BAKE_NOISE_TARGET
                                                                 : OMIS_BAKE_COMPLETE;
        out.seconds = s.seconds;
        out.samples = s.samples;
        out.raysTraced = s.rays_traced;
        out.samplesPerTexel = s.samples_per_texel;
        out.meanRelativeError = s.mean_relative_error;
        out.maxRelativeError = s.max_relative_error;
        out.passes = s.passes;
        out.texels = s.texels;
        out.covered = s.covered;
        out.degenerateUvTriangles = s.degenerate_uv_triangles;
        return true;
    });
}

OMIS_API bool omisGetBakeResultWork(OMISBakeResult result, OMISBakeWork* work) {
    return guarded(false, [&] {
        const auto& s = checked(result, "result")->result.stats;
        OMISBakeWork& out = *checked(work, "work");
        out.draws = s.draws;
        out.drawsPerTexel = s.draws_per_texel;
        out.shadowedTexels = s.shadowed_texels;
        return true;
    });
}

OMIS_API uint64_t omisGetBakeResultBuriedTexels(OMISBakeResult result) {
    return guarded<uint64_t>(0, [&] {
        return uint64_t(checked(result, "result")->result.stats.buried_texels);
    });
}

namespace {

void to_c(const omis::HalvingPrediction& p, OMISBakeHalving& out) {
    out.seconds = p.seconds;
    out.beta = p.beta;
    out.passesFitted = p.passes_fitted;
}

}  // namespace

OMIS_API int omisGetBakeResultConvergence(OMISBakeResult result, OMISBakePass* passes,
                                          int capacity) {
    return guarded(-1, [&] {
        const auto& history = checked(result, "result")->result.stats.convergence;
        if (capacity < 0) throw std::invalid_argument("capacity: must not be negative");
        const int n = int(history.size());
        if (capacity > 0) checked(passes, "passes");
        for (int i = 0; i < std::min(n, capacity); ++i) {
            passes[i].samplesPerTexel = history[i].samples_per_texel;
            passes[i].seconds = history[i].seconds;
            passes[i].meanRelativeError = history[i].mean_relative_error;
        }
        return n;
    });
}

OMIS_API bool omisGetBakeResultHalving(OMISBakeResult result, OMISBakeHalving* halving) {
    return guarded(false, [&] {
        const auto& prediction = checked(result, "result")->result.stats.halving;
        to_c(prediction, *checked(halving, "halving"));
        return true;
    });
}

OMIS_API bool omisPredictBakeHalving(const OMISBakePass* passes, int numPasses,
                                     OMISBakeHalving* halving) {
    return guarded(false, [&] {
        OMISBakeHalving& out = *checked(halving, "halving");
        if (numPasses < 0) throw std::invalid_argument("numPasses: must not be negative");
        if (numPasses > 0) checked(passes, "passes");
        std::vector<omis::BakePassRecord> history(static_cast<std::size_t>(numPasses));
        for (int i = 0; i < numPasses; ++i) {
            const OMISBakePass& p = passes[i];
            if (!std::isfinite(p.seconds) || p.seconds < 0)
                throw std::invalid_argument("passes: entry " + std::to_string(i) +
                                            " has seconds that are negative or not finite");
            if (!std::isfinite(p.meanRelativeError) || p.meanRelativeError < 0)
                throw std::invalid_argument("passes: entry " + std::to_string(i) +
                                            " has an error that is negative or not finite");
            history[i] = {p.samplesPerTexel, p.seconds, p.meanRelativeError};
        }
        to_c(omis::predict_halving(history), out);
        return true;
    });
}

OMIS_API size_t omisGetBakeResultPlan(OMISBakeResult result, char* buffer, size_t size) {
    return guarded<size_t>(0, [&] {
        return copy_text(checked(result, "result")->result.stats.plan, buffer, size);
    });
}

OMIS_API bool omisWriteBakeResultEXR(OMISBakeResult result, const char* path) {
    return guarded(false, [&] {
        const auto& r = checked(result, "result")->result;
        omis::ImageChannels image;
        image.width = r.width;
        image.height = r.height;
        image.names = {"R", "G", "B", "noise", "mask"};
        const std::size_t n = std::size_t(r.width) * r.height;
        image.pixels.resize(n * 5);
        for (std::size_t i = 0; i < n; ++i) {
            for (int c = 0; c < 3; ++c) image.pixels[5 * i + c] = r.value[3 * i + c];
            image.pixels[5 * i + 3] = r.noise[i];
            image.pixels[5 * i + 4] = r.mask[i];
        }
        omis::write_exr(checked(path, "path"), image);
        return true;
    });
}

OMIS_API bool omisWriteBakeResultPNG(OMISBakeResult result, const char* path, const char* view,
                                     const char* display, double exposure) {
    return guarded(false, [&] {
        const auto& r = checked(result, "result")->result;
        omis::DisplaySettings settings;
        if (view) settings.view = view;
        if (display) settings.display = display;
        settings.exposure = exposure;
        omis::write_png(checked(path, "path"), r.width, r.height, r.value.data(), settings);
        return true;
    });
}

OMIS_API size_t omisGetBakeTileCount(OMISBake bake) {
    return guarded<size_t>(0, [&] {
        auto* b = checked(bake, "bake");
        if (!b->committed)
            throw ApiError(OMIS_ERROR_INVALID_OPERATION,
                           "bake: not committed (call omisCommitBake first)");
        if (b->settings.target != omis::BakeTarget::Lightmap)
            throw std::invalid_argument("bake: tiles are counted for lightmaps only");
        return omis::bake_tile_count(b->settings.width, b->settings.height);
    });
}

OMIS_API OMISBakeResult omisComposeBakeResult(OMISBake bake, const float* value,
                                              const float* noise, const float* mask) {
    return guarded<OMISBakeResult>(nullptr, [&] {
        auto* b = checked(bake, "bake");
        if (!b->committed)
            throw ApiError(OMIS_ERROR_INVALID_OPERATION,
                           "bake: not committed (call omisCommitBake first)");
        const omis::BakeSettings& s = b->settings;
        if (s.target != omis::BakeTarget::Lightmap)
            throw std::invalid_argument("bake: results are composed for lightmaps only");
        ScopedRetain hold(b);
        const std::size_t n = std::size_t(s.width) * std::size_t(s.height);
        auto result = std::make_unique<OMISBakeResultImpl>();
        omis::BakeResult& r = result->result;
        r.width = s.width;
        r.height = s.height;
        r.value.assign(checked(value, "value"), value + 3 * n);
        r.noise.assign(checked(noise, "noise"), noise + n);
        r.mask.assign(checked(mask, "mask"), mask + n);
        r.samples.assign(n, 0);
        r.stats.texels = n;
        for (float m : r.mask) r.stats.covered += m > 0;
        omis::fill_bake_margin(b->scene->committed_scene("bake"), s, r.value.data(), r.noise.data());
        return result.release();
    });
}
