// Emitter-scaling benchmark (issue 8): time per texel-sample as the number of
// emitters grows — an emissive UV sphere from 16 to ~100k triangles (also over
// a plate that shadows half the floor: "shadowed sphere"), grids of 1 to 10k
// point lights and of 1 to 10k small area lights — each over a floor
// of 32×32 receivers, with the effect plan's default techniques (which switch
// to the light tree past 16 integrated emitters and to drawn delta lights
// past 64).
//
// One thread, its CPU time (the machine is shared; a per-sample cost is what
// is compared),
// every scene timed in the same run, the fastest of 5 repetitions of shading
// every receiver (interleaved over the scenes); the one-off setup (light
// tree, tables) is shown apart, and before it the scene's commit (its Embree
// scenes: the meshes with the emitter candidates, and the emitter shapes). The last
// column is the growth against the smallest scene of the same family: the
// target is at most 2× from 16 to 100k emitters.
//
// Also per scene: the estimates' variance per sample relative to their
// squared mean ("relvar/s", the mean over receivers), and a hash of every
// estimate's bits (a change that keeps the estimates bit-identical keeps it).
//
// Flags: --quick (fewer receivers), --only sphere|shadowed|race|point|area, --emitters N
// (only the scenes of N emitters: for profiling one scene), --reps N
// (repetitions, 5 unless given: more for a profile), --texels (each receiver
// spreads its samples over its grid cell, as a bake's texel does: every
// sample at its own position), --rounds N (4 unless given), --general (each
// scene also without DirectLightingSettings::fast_paths, in the same run: a
// family of its own, "… general"), --techniques A,B (those techniques, one
// sample each a round, instead of the effect plan's: to compare selections),
// --per-triangle (emissive meshes as a light per triangle, never one mesh
// light: Scene::set_mesh_lights(false); the light tree's scaling).
#include <tbb/global_control.h>

#include <algorithm>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "render/direct_lighting.h"
#include "support/emissive_sphere.h"

using namespace omis;

namespace {

void add_floor(Scene& scene) {
    scene.add_mesh(std::vector<Vec3>{{-5, -5, 0}, {5, -5, 0}, {5, 5, 0}, {-5, 5, 0}},
                   {{0, 1, 2}, {0, 2, 3}});
}

// A UV sphere of radius 0.5 at height 1.5 with `stacks`×`slices` quads (caps
// as triangles): 2·slices·(stacks − 1) triangles, emitting 1 W/(m² sr).
void add_emissive_sphere(Scene& scene, int stacks, int slices) {
    testing::add_emissive_sphere(scene, Vec3(0, 0, 1.5), 0.5, stacks, slices);
}

// side × side lights over [−2, 2]² at height 1, total power independent of
// the count.
void add_point_grid(Scene& scene, int side) {
    for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
            const Vec3 p(side == 1 ? 0 : -2 + 4.0 * i / (side - 1),
                         side == 1 ? 0 : -2 + 4.0 * j / (side - 1), 1);
            scene.add_light(make_point_light(p, Vec3(1, 1, 1) * (10.0 / (side * side)), 0));
        }
}

void add_area_grid(Scene& scene, int side) {
    const double s = 0.05;
    for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
            const Vec3 c(side == 1 ? 0 : -2 + 4.0 * i / (side - 1),
                         side == 1 ? 0 : -2 + 4.0 * j / (side - 1), 1);
            // Edges (0,s,0)×(s,0,0): emits toward −z, the floor.
            scene.add_light(make_rect_light(c - Vec3(s / 2, s / 2, 0), Vec3(0, s, 0),
                                            Vec3(s, 0, 0), Vec3(1, 1, 1) * (400.0 / (side * side)),
                                            false, kPi));
        }
}

// CPU time of this thread (s): on the shared machine, time spent waiting for
// a core is not the code's.
double cpu_seconds() {
    timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// One scene ready to shade: its lighting context (the light tree is built
// here, once per bake) and a shader, over a grid × grid floor of receivers.
struct Timed {
    std::string family, techniques;
    int emitters = 0;
    Scene scene;
    DirectLightingSettings settings;
    std::unique_ptr<LightingContext> context;
    std::unique_ptr<PointLighting> shader;
    std::vector<Vec3> points;
    double commit_ms = 0, setup_ms = 0, best = 1e300;  // best: fastest shading of every receiver (s)
    // Of the last shading: the mean over receivers of the value and of its
    // variance (channel means), and a hash of every value's bits (estimates
    // bit-identical across builds hash alike).
    double mean_value = 0, mean_variance = 0;
    std::uint64_t values_hash = 0;

    // A receiver's grid cell on the floor (--texels).
    struct Cell : Footprint {
        Vec3 centre;
        double side = 0;
        SurfacePoint at(double u, double v) const override {
            const Vec3 n(0, 0, 1);
            return {centre + Vec3((u - 0.5) * side, (v - 0.5) * side, 0), n, n};
        }
    };
    bool texels = false;
    double cell = 0;

    // extent: the side of the square of receivers about the origin.
    Timed(std::string family_, int emitters_, const std::function<void(Scene&)>& build,
          int grid, bool texels_, int rounds, bool fast_paths, double extent = 4.0,
          const std::vector<Technique>& forced = {}, bool mesh_lights = true)
        : family(std::move(family_) + (fast_paths ? "" : " general")), emitters(emitters_), texels(texels_), cell(extent / grid) {
        add_floor(scene);
        build(scene);
        scene.set_mesh_lights(mesh_lights);
        const double c0 = cpu_seconds();
        scene.commit();  // the Embree scenes (meshes and emitter candidates)
        commit_ms = 1e3 * (cpu_seconds() - c0);
        default_techniques(scene, settings.techniques, settings.samples);
        if (!forced.empty()) {
            settings.techniques = forced;
            settings.samples.assign(forced.size(), 1);
        }
        settings.rounds = rounds;
        settings.fast_paths = fast_paths;
        for (int j = 0; j < grid; ++j)
            for (int i = 0; i < grid; ++i)
                points.emplace_back(-0.5 * extent + extent * (i + 0.5) / grid,
                                    -0.5 * extent + extent * (j + 0.5) / grid, 0);
        const double t0 = cpu_seconds();
        context = std::make_unique<LightingContext>(scene, settings);
        setup_ms = 1e3 * (cpu_seconds() - t0);
        shader = std::make_unique<PointLighting>(*context);
        for (const Technique& t : settings.techniques)
            techniques += (techniques.empty() ? "" : "+") + t.name();
        if (techniques.empty()) techniques = "(delta only)";
    }

    void shade_all() {
        std::vector<double> values(3 * points.size()), variances(3 * points.size());
        const Vec3 n(0, 0, 1);
        const double start = cpu_seconds();
        for (std::size_t i = 0; i < points.size(); ++i) {
            double* value = &values[3 * i];
            double* variance = &variances[3 * i];
            if (!texels) {
                shader->shade(i, 0, settings.rounds, points[i], n, n, value, variance);
                continue;
            }
            Cell footprint;
            footprint.centre = points[i];
            footprint.side = cell;
            shader->shade(i, 0, settings.rounds, {points[i], n, n}, &footprint, value, variance);
        }
        best = std::min(best, cpu_seconds() - start);
        mean_value = mean_variance = 0;
        values_hash = 1469598103934665603ull;  // FNV-1a
        for (std::size_t i = 0; i < values.size(); ++i) {
            mean_value += values[i] / double(values.size());
            mean_variance += variances[i] / double(values.size());
            std::uint64_t bits;
            std::memcpy(&bits, &values[i], sizeof bits);
            values_hash = (values_hash ^ bits) * 1099511628211ull;
        }
    }

    int samples_per_point() const {
        int per_point = 0;
        for (int c : settings.samples) per_point += c * settings.rounds;
        return per_point;
    }
    // The estimate's variance times its samples, over its squared mean: a
    // per-sample relative variance, comparable across sample counts.
    double relative_variance_per_sample() const {
        return mean_value > 0 ? mean_variance * samples_per_point() / (mean_value * mean_value)
                              : 0.0;
    }

    double us_per_sample() const {
        // Texel-samples per point: the MIS samples; in delta-only scenes, one
        // per round (a round draws one delta light, or loops over few).
        int per_point = samples_per_point();
        if (per_point == 0) per_point = settings.rounds;
        return 1e6 * best / (double(points.size()) * per_point);
    }
};

}  // namespace

int main(int argc, char** argv) {
    bool quick = false;
    std::string only;  // --only FAMILY: time one family (for profiling)
    int only_emitters = 0;  // --emitters N: only scenes of N emitters
    int reps = 5, rounds = 4;
    bool texels = false, general = false;
    std::vector<Technique> forced;  // --techniques
    bool mesh_lights = true;        // not --per-triangle
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--quick") == 0) quick = true;
        else if (std::strcmp(argv[i], "--only") == 0 && i + 1 < argc) only = argv[++i];
        else if (std::strcmp(argv[i], "--emitters") == 0 && i + 1 < argc)
            only_emitters = std::atoi(argv[++i]);
        else if (std::strcmp(argv[i], "--reps") == 0 && i + 1 < argc)
            reps = std::max(1, std::atoi(argv[++i]));
        else if (std::strcmp(argv[i], "--rounds") == 0 && i + 1 < argc)
            rounds = std::max(1, std::atoi(argv[++i]));
        else if (std::strcmp(argv[i], "--texels") == 0) texels = true;
        else if (std::strcmp(argv[i], "--general") == 0) general = true;
        else if (std::strcmp(argv[i], "--per-triangle") == 0) mesh_lights = false;
        else if (std::strcmp(argv[i], "--techniques") == 0 && i + 1 < argc) {
            std::string list = argv[++i];
            for (std::size_t start = 0; start <= list.size();) {
                const std::size_t end = std::min(list.find(',', start), list.size());
                const auto t = parse_technique(list.substr(start, end - start));
                if (!t) {
                    std::fprintf(stderr, "unknown technique '%s'\n",
                                 list.substr(start, end - start).c_str());
                    return 2;
                }
                forced.push_back(*t);
                start = end + 1;
            }
        }
        else {
            std::fprintf(stderr, "usage: %s [--quick] [--only sphere|shadowed|race|point|area] [--emitters N] [--reps N] [--texels] [--rounds N] [--general] [--techniques A,B] [--per-triangle]\n",
                         argv[0]);
            return 2;
        }
    }
    const auto wanted = [&](const char* family, int emitters) {
        return (only.empty() || only == family) && (!only_emitters || only_emitters == emitters);
    };
    const int grid = quick ? 12 : 32;
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);

    std::vector<std::unique_ptr<Timed>> scenes;
    for (bool fast : {true, false}) {
        if (!fast && !general) break;
        const std::pair<int, int> spheres[] = {{2, 8}, {8, 16}, {20, 40}, {64, 128}, {158, 316}};
        for (auto [stacks, slices] : spheres)
            if (wanted("sphere", 2 * slices * (stacks - 1)))
                scenes.push_back(std::make_unique<Timed>(
                    "emissive sphere", 2 * slices * (stacks - 1),
                    [&](Scene& s) { add_emissive_sphere(s, stacks, slices); }, grid, texels, rounds, fast, 4.0, forced, mesh_lights));
        // The sphere over an opaque plate that shadows half of the floor:
        // many light samples there see nothing (their integrand is 0).
        for (auto [stacks, slices] : spheres)
            if (wanted("shadowed", 2 * slices * (stacks - 1)))
                scenes.push_back(std::make_unique<Timed>(
                    "shadowed sphere", 2 * slices * (stacks - 1),
                    [&](Scene& s) {
                        add_emissive_sphere(s, stacks, slices);
                        s.add_mesh(std::vector<Vec3>{{0, -3, 0.8}, {3, -3, 0.8}, {3, 3, 0.8},
                                                     {0, 3, 0.8}},
                                   {{0, 1, 2}, {0, 2, 3}});
                    },
                    grid, texels, rounds, fast, 4.0, forced, mesh_lights));
        if (wanted("race", 16129))
            scenes.push_back(std::make_unique<Timed>("race mesh", 16129, testing::add_race_mesh,
                                                     grid, texels, rounds, fast, 2.0, forced, mesh_lights));
        for (int side : {1, 4, 16, 100})
            if (wanted("point", side * side))
                scenes.push_back(std::make_unique<Timed>(
                    "point lights", side * side, [&](Scene& s) { add_point_grid(s, side); }, grid, texels, rounds, fast, 4.0, forced, mesh_lights));
        for (int side : {1, 4, 16, 100})
            if (wanted("area", side * side))
                scenes.push_back(std::make_unique<Timed>(
                    "area lights", side * side, [&](Scene& s) { add_area_grid(s, side); }, grid, texels, rounds, fast, 4.0, forced, mesh_lights));
    }
    // Repetitions interleaved over the scenes, the fastest of each kept: a
    // burst of load on the shared machine then slows one repetition of every
    // scene alike rather than all of one scene.
    for (int rep = 0; rep < reps; ++rep)
        for (auto& t : scenes) t->shade_all();

    std::printf("time per texel-sample, one thread, %d receivers%s, %d rounds of the default "
                "techniques\n", grid * grid, texels ? " (texels: samples over each cell)" : "",
                rounds);
    std::printf("%-16s %9s %12s %8s %9s %9s %9s %16s  %s\n", "scene", "emitters", "us/sample",
                "growth", "commit ms", "setup ms", "relvar/s", "values hash", "techniques");
    double base = 0;
    std::string family;
    for (const auto& t : scenes) {
        if (t->family != family) {
            family = t->family;
            base = t->us_per_sample();
        }
        std::printf("%-16s %9d %12.3f %7.2fx %9.2f %9.2f %9.4f %016llx  %s\n", t->family.c_str(),
                    t->emitters, t->us_per_sample(), t->us_per_sample() / base, t->commit_ms,
                    t->setup_ms, t->relative_variance_per_sample(),
                    (unsigned long long)t->values_hash, t->techniques.c_str());
    }
    return 0;
}
