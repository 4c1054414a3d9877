// omis.bake_uv, omis.bake_vertices and their BakeResult.
#include "interrupt.h"
#include "scene.h"

namespace omis_py {
namespace {

py::list convergence_list(const std::vector<OMISBakePass>& passes) {
    py::list out;
    for (const OMISBakePass& p : passes) {
        py::dict r;
        r["samples_per_texel"] = p.samplesPerTexel;
        r["seconds"] = p.seconds;
        r["mean_relative_error"] = p.meanRelativeError;
        out.append(r);
    }
    return out;
}

void add_halving(py::dict& d, const OMISBakeHalving& h) {
    d["halving_seconds"] = h.seconds;
    d["halving_beta"] = h.beta;
    d["halving_passes_fitted"] = h.passesFitted;
    d["halving_measured"] = h.passesFitted >= 2;
}

// omis.predict_halving: the prediction from any history, as records with the
// keys of stats["convergence"].
py::dict predict_halving(const py::iterable& history) {
    std::vector<OMISBakePass> passes;
    for (const py::handle& item : history) {
        if (!py::isinstance<py::dict>(item))
            bad("history", "expected dicts with samples_per_texel, seconds, mean_relative_error");
        const py::dict r = py::reinterpret_borrow<py::dict>(item);
        for (const char* key : {"seconds", "mean_relative_error"})
            if (!r.contains(key)) bad("history", std::string("a record has no '") + key + "'");
        OMISBakePass p{};
        p.samplesPerTexel = r.contains("samples_per_texel")
                                ? number_arg(r["samples_per_texel"], "samples_per_texel")
                                : 0.0;
        p.seconds = number_arg(r["seconds"], "seconds");
        p.meanRelativeError = number_arg(r["mean_relative_error"], "mean_relative_error");
        passes.push_back(p);
    }
    OMISBakeHalving h{};
    if (!omisPredictBakeHalving(passes.data(), int(passes.size()), &h)) raise_pending_error();
    py::dict d;
    add_halving(d, h);
    return d;
}

// A finished bake: arrays with row 0 at the bottom (Blender's Image.pixels
// order), statistics, and atomic file writers.
class BakeResult {
public:
    BakeResult(OMISBakeResult result, bool lightmap) : ref_(result), lightmap_(lightmap) {
        if (!omisGetBakeResultSize(ref_.get(), &width_, &height_)) raise_pending_error();
    }

    py::array value() const { return array("value", 3); }
    py::array noise() const { return array("noise", 1); }
    py::array mask() const { return array("mask", 1); }

    py::dict stats() const {
        OMISBakeStats s{};
        if (!omisGetBakeResultStats(ref_.get(), &s)) raise_pending_error();
        static const char* status[] = {"complete", "time budget reached", "noise target reached"};
        py::dict d;
        d["status"] = status[std::clamp(int(s.status), 0, 2)];
        d["seconds"] = s.seconds;
        d["samples"] = s.samples;
        d["rays_traced"] = s.raysTraced;
        d["samples_per_texel"] = s.samplesPerTexel;
        d["mean_relative_error"] = s.meanRelativeError;
        d["max_relative_error"] = s.maxRelativeError;
        d["passes"] = s.passes;
        d["texels"] = s.texels;
        d["covered"] = s.covered;
        d["degenerate_uv_triangles"] = s.degenerateUvTriangles;
        OMISBakeWork work{};
        if (!omisGetBakeResultWork(ref_.get(), &work)) raise_pending_error();
        d["draws"] = work.draws;
        d["draws_per_texel"] = work.drawsPerTexel;
        d["shadowed_texels"] = work.shadowedTexels;
        d["buried_texels"] = omisGetBakeResultBuriedTexels(ref_.get());
        const size_t n = omisGetBakeResultPlan(ref_.get(), nullptr, 0);
        std::string plan(n + 1, '\0');
        omisGetBakeResultPlan(ref_.get(), &plan[0], plan.size());
        plan.resize(n);
        d["plan"] = plan;
        add_convergence(d);
        return d;
    }

    void write_exr(const std::string& path) const {
        bool ok;
        {
            py::gil_scoped_release release;
            ok = omisWriteBakeResultEXR(ref_.get(), c_string(path, "path"));
        }
        if (!ok) raise_pending_error();
    }

    void write_png(const std::string& path, const std::string& view, const std::string& display,
                   double exposure) const {
        c_string(path, "path");
        c_string(view, "view");
        c_string(display, "display");
        if (!std::isfinite(exposure)) bad("exposure", "must be a finite number of stops");
        bool ok;
        {
            py::gil_scoped_release release;
            ok = omisWriteBakeResultPNG(ref_.get(), path.c_str(), view.c_str(), display.c_str(),
                                        exposure);
        }
        if (!ok) raise_pending_error();
    }

    std::string repr() const {
        return "<omis.BakeResult " + std::to_string(width_) + "×" + std::to_string(height_) +
               (lightmap_ ? " lightmap>" : " points>");
    }

private:
    // The history per pass and the halving prediction from it (omis.h).
    void add_convergence(py::dict& d) const {
        const int n = omisGetBakeResultConvergence(ref_.get(), nullptr, 0);
        if (n < 0) raise_pending_error();
        std::vector<OMISBakePass> passes(std::size_t(n) + 1);
        omisGetBakeResultConvergence(ref_.get(), passes.data(), n);
        passes.resize(std::size_t(n));
        OMISBakeHalving h{};
        if (!omisGetBakeResultHalving(ref_.get(), &h)) raise_pending_error();
        d["convergence"] = convergence_list(passes);
        add_halving(d, h);
    }

    py::array array(const char* name, int channels) const {
        const float* data = omisGetBakeResultData(ref_.get(), name);
        if (!data) raise_pending_error();
        std::vector<py::ssize_t> shape;
        if (lightmap_) shape = {height_, width_};
        else shape = {width_};
        if (channels > 1) shape.push_back(channels);
        py::array_t<float> out(shape);
        std::memcpy(out.mutable_data(), data, sizeof(float) * size_t(out.size()));
        return std::move(out);
    }

    omis::capi::BakeResultRef ref_;
    bool lightmap_;
    int width_ = 0, height_ = 0;
};

struct BakeOptions {
    py::object techniques, counts;
    long long samples;
    std::string strategy;
    double beta, cutoff;
    py::object time_budget, noise_target;
    py::object seed;
    bool smooth_normals;
    py::object progress;
    int threads;
    std::string margin_type = "extend";   // lightmaps: "extend" or "adjacent-faces"
    long long first_tile = 0, tile_count = 0;  // lightmaps: a tile range (0 tiles: all)
};

BakeResult run_bake(const Scene& scene, unsigned int mesh, OMISBakeTarget target, int width,
                    int height, int margin, const BakeOptions& o) {
    if (!o.progress.is_none() && !PyCallable_Check(o.progress.ptr()))
        bad("progress", "expected a callable taking the fraction done");
    omis::capi::BakeRef bake(omisNewBake(scene.get(), target, mesh));
    if (!bake) raise_pending_error();
    OMISBake b = bake.get();
    auto check = [] {
        const char* message = nullptr;
        const OMISError code = omisGetError(&message);
        if (code != OMIS_ERROR_NONE) raise_error(code, message ? message : "bake: error");
    };
    if (target == OMIS_BAKE_LIGHTMAP) {
        if (width < 1 || height < 1)
            bad("width, height", "must be positive, got " + std::to_string(width) + "×" +
                                     std::to_string(height));
        omisSetBakeInt(b, "width", width);
        omisSetBakeInt(b, "height", height);
        if (margin < 0) bad("margin", "must not be negative");
        omisSetBakeInt(b, "margin", margin);
        if (o.margin_type != "extend" && o.margin_type != "adjacent-faces")
            bad("margin_type", "expected 'extend' or 'adjacent-faces', got '" + o.margin_type + "'");
        omisSetBakeString(b, "marginType", o.margin_type.c_str());
        if (o.first_tile < 0 || o.tile_count < 0)
            bad("tiles", "first_tile and tile_count must not be negative");
        if (o.first_tile > 0 || o.tile_count > 0) {
            omisSetBakeInt(b, "firstTile", o.first_tile);
            omisSetBakeInt(b, "tileCount", o.tile_count);
        }
    }
    if (o.samples < 1) bad("samples", "the sample budget must be at least 1");
    omisSetBakeInt(b, "samples", o.samples);
    omisSetBakeInt(b, "seed", std::int64_t(seed_value(o.seed)));
    omisSetBakeInt(b, "smoothNormals", o.smooth_normals);
    if (o.threads < 0) bad("threads", "must be ≥ 0 (0 = all cores)");
    omisSetBakeInt(b, "threads", o.threads);
    omisSetBakeString(b, "strategy", c_string(o.strategy, "strategy"));
    omisSetBakeFloat(b, "beta", o.beta);
    omisSetBakeFloat(b, "cutoff", o.cutoff);
    if (!o.time_budget.is_none()) {
        const double t = number_arg(o.time_budget, "time_budget");
        if (!(t > 0) || !std::isfinite(t)) bad("time_budget", "expected seconds > 0, or None");
        omisSetBakeFloat(b, "timeBudget", t);
    }
    if (!o.noise_target.is_none()) {
        const double t = number_arg(o.noise_target, "noise_target");
        if (!(t > 0) || !std::isfinite(t))
            bad("noise_target", "expected a relative standard error > 0, or None");
        omisSetBakeFloat(b, "noiseTarget", t);
    }
    if (o.techniques.is_none()) {
        if (!o.counts.is_none())
            bad("counts", "given without techniques (techniques=None lets the effect plan "
                          "choose techniques and counts)");
    } else {
        // One count per technique per round, 1 each unless given.
        py::object counts = o.counts;
        if (counts.is_none()) {
            std::size_t n;
            if (py::isinstance<py::str>(o.techniques)) {
                const std::string list = o.techniques.cast<std::string>();
                n = 1 + std::count(list.begin(), list.end(), ',');
            } else {
                n = py::len(o.techniques);
            }
            py::array_t<int> ones(static_cast<py::ssize_t>(n));
            std::fill(ones.mutable_data(), ones.mutable_data() + n, 1);
            counts = std::move(ones);
        }
        TechniqueArgs t;
        try {
            t = technique_args(o.techniques, counts);
        } catch (const py::value_error& e) {
            // technique_args names `samples`; here the per-round counts are `counts`.
            std::string message = e.what();
            if (message.rfind("samples:", 0) == 0) message = "counts:" + message.substr(8);
            throw py::value_error(message);
        }
        long long per_round = 0;
        for (std::size_t k = 0; k < t.samples.size(); ++k) {
            if (t.samples[k] < 0) bad("counts", "entry " + std::to_string(k) + " is negative");
            per_round += t.samples[k];
        }
        // samples is the per-texel budget, spent in whole rounds of sum(counts);
        // counts the caller wrote must fit it (default counts: at least one round).
        if (!o.counts.is_none() && per_round > o.samples)
            bad("samples", "the budget of " + std::to_string(o.samples) +
                               " per texel is less than one round of counts (" +
                               std::to_string(per_round) + "); raise samples or lower counts");
        omisSetBakeString(b, "techniques", t.names.c_str());
        omisSetBakeCounts(b, t.samples.data(), int(t.samples.size()));
    }
    check();
    omisCommitBake(b);
    check();

    OMISBakeResult result = nullptr;
    run_interruptible("bake", o.progress, [&](NativeRun& run) {
        omisSetBakeProgressFunction(b, on_progress, &run);
        result = omisExecuteBake(b);
        return result != nullptr;
    });
    return BakeResult(result, target == OMIS_BAKE_LIGHTMAP);
}

BakeResult bake_uv(const Scene& scene, unsigned int mesh, int width, int height,
                   const py::object& techniques, const py::object& counts, long long samples,
                   const std::string& strategy, double beta, double cutoff,
                   const py::object& time_budget, const py::object& noise_target, int margin,
                   const py::object& seed, bool smooth_normals, const py::object& progress,
                   int threads, const std::string& margin_type, long long first_tile,
                   long long tile_count) {
    return run_bake(scene, mesh, OMIS_BAKE_LIGHTMAP, width, height, margin,
                    {techniques, counts, samples, strategy, beta, cutoff, time_budget,
                     noise_target, seed, smooth_normals, progress, threads, margin_type,
                     first_tile, tile_count});
}

// The tiles of a lightmap bake (16×16 texels each, row-major from the bottom).
std::size_t bake_tile_count(int width, int height) {
    if (width < 1 || height < 1) bad("width, height", "must be positive");
    return (std::size_t(width) + 15) / 16 * ((std::size_t(height) + 15) / 16);
}

// A lightmap put together from tile-range bakes (value (H, W, 3), noise and
// mask (H, W)), its margin filled as a whole bake of the mesh fills it.
BakeResult compose_bake_uv(const Scene& scene, unsigned int mesh, int width, int height,
                           const py::array_t<float, py::array::c_style | py::array::forcecast>& value,
                           const py::array_t<float, py::array::c_style | py::array::forcecast>& noise,
                           const py::array_t<float, py::array::c_style | py::array::forcecast>& mask,
                           int margin, const std::string& margin_type) {
    if (width < 1 || height < 1) bad("width, height", "must be positive");
    const py::ssize_t n = py::ssize_t(width) * height;
    if (value.size() != 3 * n) bad("value", "expected (height, width, 3) floats");
    if (noise.size() != n) bad("noise", "expected (height, width) floats");
    if (mask.size() != n) bad("mask", "expected (height, width) floats");
    omis::capi::BakeRef bake(omisNewBake(scene.get(), OMIS_BAKE_LIGHTMAP, mesh));
    if (!bake) raise_pending_error();
    omisSetBakeInt(bake.get(), "width", width);
    omisSetBakeInt(bake.get(), "height", height);
    omisSetBakeInt(bake.get(), "margin", margin);
    omisSetBakeString(bake.get(), "marginType", c_string(margin_type, "margin_type"));
    raise_if_pending();
    omisCommitBake(bake.get());
    raise_if_pending();
    OMISBakeResult result = omisComposeBakeResult(bake.get(), value.data(), noise.data(), mask.data());
    if (!result) raise_pending_error();
    return BakeResult(result, true);
}

BakeResult bake_vertices(const Scene& scene, unsigned int mesh, const std::string& domain,
                         const py::object& techniques, const py::object& counts,
                         long long samples, const std::string& strategy, double beta,
                         double cutoff, const py::object& time_budget,
                         const py::object& noise_target, const py::object& seed,
                         bool smooth_normals, const py::object& progress, int threads) {
    OMISBakeTarget target;
    if (domain == "POINT") target = OMIS_BAKE_VERTICES;
    else if (domain == "CORNER") target = OMIS_BAKE_CORNERS;
    else bad("domain", "expected 'POINT' or 'CORNER', got '" + domain + "'");
    return run_bake(scene, mesh, target, 0, 0, 0,
                    {techniques, counts, samples, strategy, beta, cutoff, time_budget,
                     noise_target, seed, smooth_normals, progress, threads});
}

}  // namespace

void init_bake(py::module_& m) {
    py::class_<BakeResult>(m, "BakeResult",
                           "A finished bake: value, noise and mask arrays (row 0 at the bottom, "
                           "as Blender's Image.pixels), stats, and atomic file writers.")
        .def_property_readonly("value", &BakeResult::value,
                               "E_direct/π, float32 (H, W, 3), or (count, 3) for vertex bakes")
        .def_property_readonly("noise", &BakeResult::noise,
                               "estimated relative standard error per texel")
        .def_property_readonly("mask", &BakeResult::mask, "1 where baked, 0 margin or empty")
        .def_property_readonly("stats", &BakeResult::stats,
                               "time, samples, draws, rays, errors, passes, status, the effect plan, "
                               "the convergence per pass and the halving time predicted from it")
        .def("write_exr", &BakeResult::write_exr, py::arg("path"),
             "Linear float EXR with channels R, G, B, noise, mask (atomic write).")
        .def("write_png", &BakeResult::write_png, py::arg("path"), py::arg("view") = "Standard",
             py::arg("display") = "sRGB", py::arg("exposure") = 0.0,
             "8-bit PNG through Blender's OCIO view transform (atomic write).")
        .def("__repr__", &BakeResult::repr);

    m.def("bake_uv", &bake_uv, py::arg("scene"), py::arg("mesh"), py::arg("width"),
          py::arg("height"), py::kw_only(), py::arg("techniques") = py::none(),
          py::arg("counts") = py::none(), py::arg("samples") = 64,
          py::arg("strategy") = "optimal-direct", py::arg("beta") = 2.0, py::arg("cutoff") = 0.1,
          py::arg("time_budget") = py::none(), py::arg("noise_target") = py::none(),
          py::arg("margin") = 16, py::arg("seed") = 0, py::arg("smooth_normals") = true,
          py::arg("progress") = py::none(), py::arg("threads") = 0,
          py::arg("margin_type") = "extend", py::arg("first_tile") = 0, py::arg("tile_count") = 0,
          R"doc(Bakes E_direct/π into a mesh's UV lightmap of width × height texels.

techniques: names (SPEC §3) or None for the effect plan's choice; counts: samples
of each technique per round (1 each by default); samples: the sample budget per
texel, spent in whole rounds of sum(counts) (rounded down, at least one round; given
counts whose round exceeds samples are an error). time_budget (s) and noise_target (relative standard error) stop the bake
earlier. progress(fraction) -> bool is called on this thread; False or Ctrl-C
raises omis.Cancelled / KeyboardInterrupt and nothing is returned. threads: worker
threads (0 = all cores); results do not depend on it. margin (texels) and
margin_type fill the texels around UV islands as Blender's Bake ▸ Margin does:
'extend' copies the island's nearest texel, 'adjacent-faces' the texel across
the UV seam on the face adjacent in 3D (extend where there is none).
first_tile, tile_count: bake only these of the lightmap's 16×16-texel tiles
(bake_tile_count; 0 tiles: all), each texel with the bits a whole bake gives it,
the margin left unfilled (compose_bake_uv fills it; omis.farm uses both).)doc");
    m.def("bake_tile_count", &bake_tile_count, py::arg("width"), py::arg("height"),
          "How many 16×16-texel tiles a width × height lightmap bake has.");
    m.def("compose_bake_uv", &compose_bake_uv, py::arg("scene"), py::arg("mesh"),
          py::arg("width"), py::arg("height"), py::arg("value"), py::arg("noise"), py::arg("mask"),
          py::kw_only(), py::arg("margin") = 16, py::arg("margin_type") = "extend",
          "A BakeResult from tile-range bakes' value, noise and mask put together, the margin "
          "filled as a whole bake of the mesh fills it (stats hold texels and covered only).");
    m.def("predict_halving", &predict_halving, py::arg("history"),
          R"doc(What halving a bake's mean relative error would cost, from a history of
passes (dicts as in BakeResult.stats["convergence"]: seconds, mean_relative_error,
samples_per_texel): error ∝ t^(-beta) fitted over the later passes. Returns
halving_seconds (more sampling time: t·(2^(1/beta) − 1)), halving_beta,
halving_passes_fitted and halving_measured (False: too few passes, beta = 0.5
assumed, an upper bound).)doc");
    m.def("bake_vertices", &bake_vertices, py::arg("scene"), py::arg("mesh"), py::kw_only(),
          py::arg("domain") = "POINT", py::arg("techniques") = py::none(),
          py::arg("counts") = py::none(), py::arg("samples") = 64,
          py::arg("strategy") = "optimal-direct", py::arg("beta") = 2.0, py::arg("cutoff") = 0.1,
          py::arg("time_budget") = py::none(), py::arg("noise_target") = py::none(),
          py::arg("seed") = 0, py::arg("smooth_normals") = true, py::arg("progress") = py::none(),
          py::arg("threads") = 0,
          R"doc(Bakes E_direct/π at a mesh's vertices (domain "POINT") or triangle corners
("CORNER", 3 per triangle in triangle order), as bake_uv does for texels. As in
Cycles, each corner is shaded just inside its triangle and a vertex takes the
mean of its corners.)doc");
}

}  // namespace omis_py
