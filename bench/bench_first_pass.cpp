// A bake's fixed cost (issue 9, item 5 "small bakes"): on scenes of the
// Cycles race's kind (bench/bench_cycles.py), a 128² lightmap baked with
// samples=1 against samples=16, and the phases of the first pass timed
// apart: the UV raster, the lighting context, the per-texel set-up
// (techniques and light tables: a samples=1 pass's set-up is what it costs
// beyond a later round's sampling) and the sampling.
//
//   omis_bench_first_pass [--size N] [--reps R] [--scenes a,b]
//
// --passes 1,1,2,4,8: what a later pass repeats. The receiver's texels (as
// square footprints) shaded through PointLighting as a bake's passes shade
// them, in passes of these rounds, against one pass of all of them; the
// difference per later pass, in rounds of that one pass's sampling. With
// --profile 1: the passes alone, --reps times (for perf or callgrind).
//
// Every figure is the median of R interleaved repetitions within this run;
// the machine is shared, so read the ratios, not the milliseconds.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "bake/uv_raster.h"
#include "render/direct_lighting.h"
#include "render/effect_plan.h"
#include "support/emissive_sphere.h"
#include "support/square_footprint.h"

#include <tbb/blocked_range2d.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

using namespace omis;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_of(const std::function<void()>& f) {
    const auto t0 = Clock::now();
    f();
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The race's receiver: a 2 m square at z = 0, UVs over [0, 1]².
void add_receiver(Scene& scene) {
    static const std::vector<float> positions = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    static const std::vector<std::uint32_t> triangles = {0, 1, 2, 0, 2, 3};
    static const std::vector<float> uvs = {0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 1};
    static const std::vector<float> normals = {0, 0, 1, 0, 0, 1, 0, 0, 1,
                                               0, 0, 1, 0, 0, 1, 0, 0, 1};  // as exported
    MeshInput m;
    m.name = "receiver";
    m.positions = ScalarArray::of(positions.data(), 4, 3);
    m.triangles = IndexArray{triangles.data(), 2, 3};
    m.uvs = ScalarArray::of(uvs.data(), 6, 2);
    m.normals = ScalarArray::of(normals.data(), 6, 3);
    scene.add_mesh(m);
}

void add_box(Scene& scene, const Vec3& c, const Vec3& h) {
    std::vector<Vec3> v;
    for (int i = 0; i < 8; ++i)
        v.push_back(c + Vec3(i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z));
    scene.add_mesh(v, {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                       {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}});
}

// bench_cycles.py's scenes, as omis sees them after export (edges' lengths
// and places as there; rotations approximate).
std::map<std::string, std::function<void(Scene&)>> scenes() {
    std::map<std::string, std::function<void(Scene&)>> s;
    s["area"] = [](Scene& scene) {
        add_receiver(scene);
        scene.add_light(make_rect_light(Vec3(-0.75, -0.45, 0.85), Vec3(0, 0.5, 0),
                                        Vec3(0.47, 0, -0.17), Vec3(20, 20, 20), false, kPi));
        scene.add_light(make_rect_light(Vec3(0.1, 0.15, 0.6), Vec3(-0.15, 0.26, 0.0),
                                        Vec3(0.78, 0.45, 0.0), Vec3(40, 40, 40), false,
                                        0.5 * kPi));
    };
    s["emissive_mesh"] = [](Scene& scene) {
        add_receiver(scene);
        omis::testing::add_race_mesh(scene);
    };
    s["area_round"] = [](Scene& scene) {
        add_receiver(scene);
        const Vec3 a = normalize(Vec3(0, 1, -0.47)) * 0.3;
        scene.add_light(make_ellipse_light(Vec3(0, -0.4, 0.7), a, Vec3(0.3, 0, 0),
                                           Vec3(30, 30, 30), false, 2 * kPi / 3));
        scene.add_light(make_ellipse_light(Vec3(0.3, 0.5, 0.5), Vec3(-0.1, 0.11, 0),
                                           Vec3(0.22, 0.2, -0.1), Vec3(20, 20, 20), false,
                                           kPi));
    };
    s["emission_world"] = [](Scene& scene) {
        add_receiver(scene);
        scene.add_mesh({{-0.1, -0.3, 0.7}, {0.5, -0.3, 0.7}, {0.5, 0.3, 0.7}, {-0.1, 0.3, 0.7}},
                       {{0, 2, 1}, {0, 3, 2}}, Vec3(6, 4.8, 3.6));
        add_box(scene, Vec3(-0.4, 0, 0.35), Vec3(0.2, 0.2, 0.025));
        scene.add_light(make_world_light(Vec3(0.15, 0.2, 0.25)));
    };
    s["world_window"] = [](Scene& scene) {
        add_receiver(scene);  // the floor of a closed room, sky through an opening
        const double h = 1.5;
        add_box(scene, Vec3(1.05, 0, h / 2), Vec3(0.05, 1.1, h / 2));
        add_box(scene, Vec3(-1.05, 0, h / 2), Vec3(0.05, 1.1, h / 2));
        add_box(scene, Vec3(0, 1.05, h / 2), Vec3(1.1, 0.05, h / 2));
        add_box(scene, Vec3(0, -1.05, h / 2), Vec3(1.1, 0.05, h / 2));
        add_box(scene, Vec3(-0.525, 0, h + 0.05), Vec3(0.575, 1.1, 0.05));
        add_box(scene, Vec3(0.825, 0, h + 0.05), Vec3(0.275, 1.1, 0.05));
        add_box(scene, Vec3(0.3, -0.575, h + 0.05), Vec3(0.25, 0.525, 0.05));
        add_box(scene, Vec3(0.3, 0.775, h + 0.05), Vec3(0.25, 0.325, 0.05));
        scene.add_light(make_rect_light(Vec3(-0.65, -0.55, 1.4), Vec3(0, 0.3, 0),
                                        Vec3(0.3, 0, 0), Vec3(35, 35, 35), false, kPi));
        scene.add_light(make_world_light(Vec3(5, 6, 8)));
    };
    s["demo_room"] = [](Scene& scene) {
        add_receiver(scene);  // the floor, 2 m of the room's 6 m
        add_box(scene, Vec3(-0.6, -0.2, 0.74), Vec3(0.8, 0.45, 0.02));
        add_box(scene, Vec3(0, 0, 2.65), Vec3(3.1, 3.1, 0.05));
        scene.add_light(make_rect_light(Vec3(-1.2, -0.5, 2.2), Vec3(0, 0.6, 0),
                                        Vec3(1.2, 0, 0), Vec3(9, 9, 9), false, kPi));
        scene.add_light(make_rect_light(Vec3(2.95, 1.0, 1.2), Vec3(0, 0, 0.5),
                                        Vec3(0, 0.8, 0), Vec3(24, 18, 12), false, kPi));
    };
    return s;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

BakeSettings settings_for(int size, long long samples) {
    BakeSettings b;
    b.width = b.height = size;
    b.margin = 0;
    b.samples = samples;
    b.lighting.strategy = Strategy::OptimalDirect;
    return b;
}

// What the first pass's set-up may not cost: error per sample. Mean over
// texels of the squared error relative to a reference (samples=1024, another
// seed), at 4 and 16 samples, over `reps` seeds.
void print_quality(const std::string& name, const std::function<void(Scene&)>& build, int size) {
    Scene scene;
    build(scene);
    scene.commit();
    BakeSettings r = settings_for(size, 1024);
    r.lighting.seed = 12345;
    const BakeResult ref = bake(scene, r);
    std::printf("%-15s relMSE", name.c_str());
    for (long long spp : {4LL, 16LL}) {
        double sum = 0;
        std::size_t n = 0;
        for (int seed = 0; seed < 4; ++seed) {
            BakeSettings b = settings_for(size, spp);
            b.lighting.seed = std::uint64_t(seed);
            const BakeResult res = bake(scene, b);
            for (std::size_t i = 0; i < ref.mask.size(); ++i) {
                const double y = ref.value[3 * i + 1];
                if (!(ref.mask[i] > 0) || !(y > 1e-3)) continue;
                const double d = (res.value[3 * i + 1] - y) / y;
                sum += d * d;
                ++n;
            }
        }
        std::printf("  %lld spp %.3e", spp, n ? sum / n : 0.0);
    }
    std::printf("\n");
}

// The receiver's size² texels as a bake's passes shade them (a tile of 16²
// texels per task, one PointLighting per thread, texel tables kept), in
// passes of `schedule` rounds; seconds.
double shade_in_passes(const Scene& scene, int size, const std::vector<int>& schedule) {
    BakeSettings b = settings_for(size, 1);
    default_techniques(scene, b.lighting.techniques, b.lighting.samples);
    b.lighting.receiver = scene.mesh_receiver(0);
    const auto t0 = Clock::now();
    LightingContext context(scene, b.lighting);
    const std::size_t count = std::size_t(size) * size;
    if (context.keeps_texel_tables) context.texel_tables.index_points(count);
    if (schedule.size() > 1) {
        context.keep_draw_counts(count);
        context.keep_table_reach(count);
        context.keep_region_radii(count);
        context.keep_region_branching(count);
    }
    tbb::enumerable_thread_specific<PointLighting> shaders([&] { return PointLighting(context); });
    const double texel = 2.0 / size;  // the 2 m receiver; footprints half a texel wide
    int first_round = 0;
    for (int rounds : schedule) {
        tbb::parallel_for(tbb::blocked_range2d<int>(0, size, 16, 0, size, 16),
                          [&](const tbb::blocked_range2d<int>& r) {
            PointLighting& shader = shaders.local();
            for (int y = r.rows().begin(); y != r.rows().end(); ++y)
                for (int x = r.cols().begin(); x != r.cols().end(); ++x) {
                    const omis::testing::SquareFootprint f(
                        Vec3(-1 + (x + 0.5) * texel, -1 + (y + 0.5) * texel, 0), texel / 4);
                    double value[3], variance[3], own[3];
                    shader.shade(std::size_t(y) * size + x, first_round, rounds, f.centre(), &f,
                                 value, variance, nullptr, own);
                }
        });
        first_round += rounds;
    }
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// --passes: per scene, the schedule against one pass of as many rounds, and
// one round alone (the set-up); interleaved repetitions, medians.
void print_passes(const std::string& name, const std::function<void(Scene&)>& build, int size,
                  int reps, const std::vector<int>& schedule) {
    Scene scene;
    build(scene);
    scene.commit();
    int total = 0;
    for (int r : schedule) total += r;
    std::vector<double> one_round, one_pass, passes;
    for (int r = 0; r < reps; ++r) {
        one_round.push_back(shade_in_passes(scene, size, {1}));
        one_pass.push_back(shade_in_passes(scene, size, {total}));
        passes.push_back(shade_in_passes(scene, size, schedule));
    }
    const double t1 = median(one_round), tn = median(one_pass), tp = median(passes);
    const double round = (tn - t1) / (total - 1);
    std::printf("%-15s %8.2f %8.2f %8.2f %8.2f %10.2f\n", name.c_str(), 1e3 * t1, 1e3 * tn,
                1e3 * tp, 1e3 * round, (tp - tn) / (schedule.size() - 1) / round);
}

}  // namespace

int main(int argc, char** argv) {
    int size = 128, reps = 7;
    std::string only;
    long long profile = 0;  // --profile S: only bakes of S samples (for perf record)
    bool quality = false;   // --quality: error per sample instead of time
    std::vector<int> schedule;  // --passes: rounds per pass
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--size") && i + 1 < argc) size = std::atoi(argv[++i]);
        else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
        else if (!std::strcmp(argv[i], "--scenes") && i + 1 < argc) only = argv[++i];
        else if (!std::strcmp(argv[i], "--profile") && i + 1 < argc) profile = std::atoll(argv[++i]);
        else if (!std::strcmp(argv[i], "--quality")) quality = true;
        else if (!std::strcmp(argv[i], "--passes") && i + 1 < argc)
            for (const char* p = argv[++i]; *p; p += *p == ',')
                schedule.push_back(int(std::strtol(p, const_cast<char**>(&p), 10)));
    }
    if (!schedule.empty() && profile > 0) {  // the passes alone, for perf or callgrind
        for (const auto& [name, build] : scenes()) {
            if (!only.empty() && ("," + only + ",").find("," + name + ",") == std::string::npos)
                continue;
            Scene scene;
            build(scene);
            scene.commit();
            for (int r = 0; r < reps; ++r) shade_in_passes(scene, size, schedule);
        }
        return 0;
    }
    if (!schedule.empty()) {
        std::printf("passes of");
        for (int r : schedule) std::printf(" %d", r);
        std::printf(" rounds: %d² texels, optimal-direct, median of %d\n"
                    "%-15s %8s %8s %8s %8s %10s\n", size, reps, "scene", "1 round",
                    "1 pass", "passes", "round", "per pass");
        for (const auto& [name, build] : scenes())
            if (only.empty() || ("," + only + ",").find("," + name + ",") != std::string::npos)
                print_passes(name, build, size, reps, schedule);
        std::printf("(milliseconds; per pass: what each later pass adds, in rounds)\n");
        return 0;
    }
    std::printf("first pass vs later rounds: %d² lightmap, optimal-direct, median of %d\n"
                "%-15s %8s %8s %8s %8s %8s %8s %8s %7s\n",
                size, reps, "scene", "commit", "raster", "context", "spp=1", "spp=16",
                "round", "set-up", "1/round");
    for (const auto& [name, build] : scenes()) {
        if (!only.empty() && ("," + only + ",").find("," + name + ",") == std::string::npos)
            continue;
        if (quality) {
            print_quality(name, build, size);
            continue;
        }
        if (profile > 0) {
            Scene scene;
            build(scene);
            scene.commit();
            for (int r = 0; r < reps; ++r) bake(scene, settings_for(size, profile));
            continue;
        }
        std::vector<double> commit, raster, context, one, sixteen;
        for (int r = 0; r < reps; ++r) {
            Scene scene;
            build(scene);
            commit.push_back(seconds_of([&] { scene.commit(); }));
            BakeSettings b = settings_for(size, 1);
            raster.push_back(seconds_of([&] { rasterize_uv(scene.geometry().mesh(0), size, size); }));
            BakeSettings with = b;
            default_techniques(scene, with.lighting.techniques, with.lighting.samples);
            context.push_back(seconds_of([&] { LightingContext c(scene, with.lighting); }));
            one.push_back(bake(scene, b).stats.seconds);
            sixteen.push_back(bake(scene, settings_for(size, 16)).stats.seconds);
        }
        // A later round: what samples=16 adds per sample beyond samples=1;
        // the set-up: what samples=1 costs beyond one such round.
        const double t1 = median(one), t16 = median(sixteen), round = (t16 - t1) / 15;
        std::printf("%-15s %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %7.2f\n", name.c_str(),
                    1e3 * median(commit), 1e3 * median(raster), 1e3 * median(context), 1e3 * t1,
                    1e3 * t16, 1e3 * round, 1e3 * (t1 - round), t1 / round);
    }
    std::printf("(milliseconds; 1/round: a samples=1 bake's cost in later rounds, target ≤ 2)\n");
    return 0;
}
