// omis.Scene's Python class and omis.direct_lighting.
#include "interrupt.h"
#include "scene.h"

namespace omis_py {
namespace {

// A committed OMISDirectLighting job for these settings; errors name the
// Python argument.
omis::capi::DirectLightingRef lighting_job(const Scene& scene, const TechniqueArgs& t, int rounds,
                                           const std::string& strategy,
                                           const py::handle& seed, double beta, double cutoff,
                                           int streams) {
    omis::capi::DirectLightingRef job(omisNewDirectLighting(scene.get()));
    if (!job) raise_pending_error();
    OMISDirectLighting l = job.get();
    if (!t.names.empty()) {
        for (std::size_t k = 0; k < t.samples.size(); ++k)
            if (t.samples[k] < 0) bad("samples", "entry " + std::to_string(k) + " is negative");
        omisSetDirectLightingString(l, "techniques", t.names.c_str());
        omisSetDirectLightingCounts(l, t.samples.data(), int(t.samples.size()));
    }
    omisSetDirectLightingInt(l, "rounds", rounds);
    omisSetDirectLightingInt(l, "streams", streams);
    omisSetDirectLightingString(l, "strategy", c_string(strategy, "strategy"));
    omisSetDirectLightingInt(l, "seed", std::int64_t(seed_value(seed)));
    omisSetDirectLightingFloat(l, "beta", beta);
    omisSetDirectLightingFloat(l, "cutoff", cutoff);
    raise_if_pending();  // the first setting refused, named
    omisCommitDirectLighting(l);
    raise_if_pending();
    return job;
}

py::dict stats_dict(const OMISDirectLightingStats& stats, const std::string& plan) {
    using namespace pybind11::literals;
    return py::dict("points"_a = stats.points, "samples"_a = stats.samples,
                    "rays_traced"_a = stats.raysTraced, "mis_systems"_a = stats.misSystems,
                    "pdf_evaluations"_a = stats.pdfEvaluations, "seconds"_a = stats.seconds,
                    "plan"_a = plan);
}

py::object direct_lighting(const Scene& scene, const py::handle& points_in,
                           const py::handle& normals_in, const py::handle& techniques,
                           const py::handle& samples, int rounds, const std::string& strategy,
                           const py::handle& seed, double beta, double cutoff, int streams,
                           const py::object& progress, bool return_stats) {
    auto points = as_float_array(points_in, "points");
    auto normals = as_float_array(normals_in, "normals");
    if (points.ndim() != 2 || points.shape(1) != 3)
        bad("points", "expected shape (P, 3), got " + shape_of(points));
    const py::ssize_t P = points.shape(0);
    if (normals.ndim() != 2 || normals.shape(0) != P || normals.shape(1) != 3)
        bad("normals", "expected shape (" + std::to_string(P) + ", 3) like points, got " +
                           shape_of(normals));
    const TechniqueArgs t = technique_args(techniques, samples);
    if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
        bad("progress", "expected a callable taking the fraction done");
    const auto job = lighting_job(scene, t, rounds, strategy, seed, beta, cutoff, streams);

    py::array_t<double> value({P, py::ssize_t(3)}), variance({P, py::ssize_t(3)});
    OMISDirectLightingStats stats{};
    run_interruptible("direct_lighting", progress, [&](NativeRun& run) {
        omisSetDirectLightingProgressFunction(job.get(), on_progress, &run);
        return omisExecuteDirectLighting(job.get(), points.data(), normals.data(), size_t(P),
                                         value.mutable_data(), variance.mutable_data(), &stats);
    });
    if (!return_stats) return py::make_tuple(value, variance);
    return py::make_tuple(value, variance, stats_dict(stats, plan_text(scene, t)));
}

}  // namespace

void init_scene(py::module_& m) {
    const double pi = 3.14159265358979323846;
    py::class_<Scene> scene(m, "Scene", R"doc(Meshes and lights for direct lighting (SPEC §3–§4).

Add meshes and lights, commit(), then light it with omis.direct_lighting.
Units: metres; radiance W/(m² sr), intensity W/sr, irradiance W/m² (RGB: three
numbers, or one for grey); angles in radians. Every add returns an integer id.)doc");
    // Rect and ellipse lights take the same arguments: a point, two perpendicular
    // vectors, radiance, sides and Blender's spread.
    struct PlanarLight {
        const char* name;
        decltype(&Scene::add_rect_light) add;
        std::array<const char*, 3> frame;
        const char* doc;
    };
    for (const PlanarLight& l :
         {PlanarLight{"add_rect_light", &Scene::add_rect_light, {"corner", "edge_u", "edge_v"},
                      "Rectangle corner + [0,1]·edge_u + [0,1]·edge_v (perpendicular edges); "
                      "one-sided lights emit toward cross(edge_u, edge_v). Returns the light id."},
          PlanarLight{"add_ellipse_light", &Scene::add_ellipse_light,
                      {"center", "axis_u", "axis_v"},
                      "Ellipse center + a·axis_u + b·axis_v, a² + b² ≤ 1 (perpendicular "
                      "semi-axes); one-sided lights emit toward cross(axis_u, axis_v). Returns "
                      "the light id."}})
        scene.def(l.name, l.add, py::arg(l.frame[0]), py::arg(l.frame[1]), py::arg(l.frame[2]),
                  py::arg("radiance"), py::arg("two_sided") = false, py::arg("spread") = pi,
                  l.doc);
    scene.def(py::init<>())
        .def("add_mesh", &Scene::add_mesh, py::arg("vertices"), py::arg("triangles"),
             py::arg("normals") = py::none(), py::arg("uvs") = py::none(),
             py::arg("emission") = py::none(),
             R"doc(Adds a triangle mesh (an occluder; also an emitter with emission).

vertices: (V, 3) float32/float64; triangles: (T, 3) integer vertex indices,
counter-clockwise = front; normals: optional (3T, 3) per-corner shading
normals; uvs: optional (3T, 2) per-corner UVs; emission: optional RGB radiance
(the mesh then emits from both sides). Returns the mesh id.)doc")
        .def("add_disk_light", &Scene::add_disk_light, py::arg("center"), py::arg("normal"),
             py::arg("radius"), py::arg("radiance"), py::arg("two_sided") = false,
             py::arg("spread") = pi,
             "Disk of the given radius emitting along normal (both ways if two_sided). "
             "Returns the light id.")
        .def("add_point_light", &Scene::add_point_light, py::arg("position"),
             py::arg("intensity"), py::arg("radius") = 0.0,
             "Point light of intensity W/sr; radius > 0 makes it a disk facing the receiver. "
             "Returns the light id.")
        .def("add_spot_light", &Scene::add_spot_light, py::arg("position"), py::arg("direction"),
             py::arg("intensity"), py::arg("spot_size"), py::arg("spot_blend") = 0.15,
             py::arg("radius") = 0.0,
             "Spot light shining along direction; spot_size is the full cone angle, "
             "spot_blend Blender's smoothstep width in [0, 1]. Returns the light id.")
        .def("add_sun_light", &Scene::add_sun_light, py::arg("direction"), py::arg("irradiance"),
             py::arg("angle") = 0.0,
             "Sun light travelling along direction; irradiance on a surface facing it; angle "
             "is the full angular diameter (0: one shadow ray). Returns the light id.")
        .def("set_world", &Scene::set_world, py::arg("radiance"),
             "Constant background radiance from every direction (replaces an earlier one). "
             "Returns the light id.")
        .def("set_world_image", &Scene::set_world_image, py::arg("image"),
             py::arg("rotation") = py::make_tuple(0.0, 0.0, 0.0), py::arg("compensate") = false,
             "Image-based world (replaces an earlier world): an equirectangular RGB radiance "
             "map, a (H, W, 3) float array with rows top first or a path to an image "
             "OpenImageIO reads (EXR, HDR), in Cycles' convention (the image's centre looks "
             "along +X, the top row is the zenith). rotation: Euler XYZ in radians as "
             "Blender's Mapping node. compensate: draw from max(0, map - mean) (MIS "
             "compensation). Returns the light id.")
        .def("set_light_flags", &Scene::set_light_flags, py::arg("light"),
             py::arg("cast_shadow") = true, py::arg("visible_to_bsdf") = true,
             "Blender's cycles.cast_shadow and use_multiple_importance_sampling for one light.")
        .def("set_mesh_lights", &Scene::set_mesh_lights, py::arg("enabled"),
             "Whether commit draws a compact emissive mesh (at least 64 triangles, its area at "
             "least 3/4 of its bounding sphere's) as one light toward its bounding sphere "
             "instead of a light per triangle (default True). Before commit.")
        .def("set_receiver", &Scene::set_receiver, py::arg("mesh"), py::arg("model"),
             py::arg("roughness") = 0.0,
             "The mesh's diffuse closure when baked, as Cycles' Diffuse bake evaluates it: "
             "'lambert' (default), 'principled' (Principled BSDF, its Roughness) or "
             "'oren-nayar' (Diffuse BSDF, its Roughness). Before commit.")
        .def("commit", &Scene::commit,
             "Builds the acceleration structure; the scene is then read-only.")
        .def("effect_plan", &effect_plan, py::arg("techniques") = py::none(),
             py::arg("samples") = py::none(),
             "The effect plan of the committed scene for these techniques (None: the "
             "default choice), as printable text.");

    m.def("direct_lighting", &direct_lighting, py::arg("scene"), py::arg("points"),
          py::arg("normals"), py::arg("techniques") = py::none(), py::arg("samples") = py::none(),
          py::arg("rounds") = 1, py::arg("strategy") = "optimal-direct", py::arg("seed") = 0,
          py::kw_only(), py::arg("beta") = 2.0, py::arg("cutoff") = 0.1, py::arg("streams") = 1,
          py::arg("progress") = py::none(), py::arg("return_stats") = false,
          R"doc(E_direct/π per RGB channel at shading points of a committed scene (SPEC §3, §6).

points, normals: (P, 3) float arrays (normals are normalised; not zero).
techniques: list of names (see TECHNIQUES: "bsdf", "<selection>/<sampler>")
or one comma-separated string, with samples: one count per technique per round;
techniques=None lets the effect plan choose both (samples must then be None).
rounds: R; strategy: a MIS strategy name (see STRATEGIES); seed: results depend on
it only, not on the thread count. beta, cutoff: heuristic options.
streams: independently randomized streams per point (1..4): 1 = one scrambled
sequence, the least error (variance is then the independent-draw formula, an
upper estimate); more = variance is the streams' measured spread.
progress: optional callable, called with the fraction done about every 50 ms on
the calling thread (and with 1.0 at the end); returning False stops the work and
raises omis.Cancelled. Ctrl-C stops it too (KeyboardInterrupt).
Returns (value, variance), (P, 3) float64 arrays, plus a stats dict (points,
samples, rays_traced, mis_systems, pdf_evaluations, seconds, plan) with
return_stats=True.)doc");
}

}  // namespace omis_py
