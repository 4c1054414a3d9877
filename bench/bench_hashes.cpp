// Bit-identity check for refactors of the lighting core: runs a fixed set of
// deterministic jobs — bakes of a floor under every kind of light (rects,
// spread and round lights, delta lights drawn and summed, a world, emissive
// meshes as one mesh light and as a light per triangle, many small lights
// through the light tree) with every strategy, several technique sets and
// options (streams, shadowed draws, the general path, sample allocation, a
// noise target, a fixed sample budget), the hard-case suite's point runs, and
// direct_lighting() at points — and prints one 64-bit FNV-1a hash per job over
// every output bit and the counters, then one over all of them. A change that
// keeps the lighting bit-identical keeps every line. No time budgets (what
// they bake depends on the clock); 2 threads (results do not depend on the
// thread count; counters neither).
//   omis_bench_hashes [name part]
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "render/direct_lighting.h"
#include "support/emissive_sphere.h"
#include "support/floor_lambert.h"
#include "support/hard_cases.h"
#include "support/lighting_settings.h"

using namespace omis;
using namespace omis::testing;

namespace {

struct Hash {
    std::uint64_t h = 1469598103934665603ull;
    void bytes(const void* p, std::size_t n) {
        const auto* b = static_cast<const unsigned char*>(p);
        for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
    }
    template <class T>
    void value(const T& v) {
        bytes(&v, sizeof v);
    }
    template <class T>
    void values(const std::vector<T>& v) {
        value(v.size());
        if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
    }
};

// The floor's arrays, which the scene reads in place.
struct Floor {
    std::vector<float> positions, uvs;
    std::vector<std::uint32_t> triangles;
};

// A 2 m floor (UVs over [0,1]²) with a small plate above part of it that
// shadows some texels, then `lights`.
void floor_scene(Scene& scene, Floor& f, const std::function<void(Scene&)>& lights) {
    f.positions = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    f.triangles = {0, 1, 2, 0, 2, 3};
    f.uvs.clear();
    for (std::uint32_t i : f.triangles)
        f.uvs.insert(f.uvs.end(),
                     {0.5f * (f.positions[3 * i] + 1), 0.5f * (f.positions[3 * i + 1] + 1)});
    scene.add_mesh(two_triangle_mesh("floor", f.positions, f.triangles, f.uvs));
    scene.add_mesh(std::vector<Vec3>{{-0.6, -0.2, 0.4}, {0.1, -0.2, 0.4}, {0.1, 0.5, 0.45},
                                     {-0.6, 0.5, 0.45}},
                   {{0, 1, 2}, {0, 2, 3}});
    lights(scene);
}

void rect_lights(Scene& s) {
    s.add_light(make_rect_light(Vec3(-0.5, -0.5, 1), Vec3(0, 1, 0), Vec3(1, 0, 0),
                                Vec3(2, 2, 2), false, kPi));
    s.add_light(make_rect_light(Vec3(0.6, -0.9, 0.3), Vec3(0, 0.2, 0), Vec3(0, 0, 0.2),
                                Vec3(30, 10, 5), false, kPi));
}
void spread_lights(Scene& s) {
    s.add_light(make_rect_light(Vec3(-0.5, -0.5, 1), Vec3(0, 1, 0), Vec3(1, 0, 0),
                                Vec3(2, 2, 2), false, 0.6));
    s.add_light(make_ellipse_light(Vec3(0.5, 0.3, 0.8), Vec3(0.3, 0, 0), Vec3(0, 0.15, 0.05),
                                   Vec3(4, 3, 2), true, 0.9));
    s.add_light(make_ellipse_light(Vec3(-0.7, 0.6, 0.5), Vec3(0.1, 0, 0), Vec3(0, 0, 0.1),
                                   Vec3(8, 8, 8), false, kPi));
}
void delta_lights(Scene& s) {
    s.add_light(make_point_light(Vec3(0.2, 0.1, 1.2), Vec3(1, 2, 3), 0));
    s.add_light(make_point_light(Vec3(-0.4, 0.3, 0.8), Vec3(2, 1, 1), 0.1));
    s.add_light(make_spot_light(Vec3(0.5, -0.5, 1), Vec3(-0.3, 0.3, -1), Vec3(5, 5, 5), 0,
                                0.9, 0.3));
    s.add_light(make_sun_light(Vec3(0.3, 0.2, -1), Vec3(1, 1, 1), 0));
    s.add_light(make_sun_light(Vec3(-0.3, 0.1, -1), Vec3(1, 0.5, 0.2), 0.1));
    s.add_light(make_rect_light(Vec3(-0.5, -0.5, 1), Vec3(0, 1, 0), Vec3(1, 0, 0),
                                Vec3(1, 1, 1), false, kPi));
}
void many_delta_lights(Scene& s) {
    for (int i = 0; i < 90; ++i)
        s.add_light(make_point_light(Vec3(-1 + 0.021 * i, 0.3 * std::sin(i), 0.5 + 0.01 * i),
                                     Vec3(0.1, 0.1 + 0.001 * i, 0.1), 0));
}
void world_lights(Scene& s) {
    s.add_light(make_world_light(Vec3(0.3, 0.4, 0.5)));
    s.add_light(make_rect_light(Vec3(-0.2, -0.2, 0.7), Vec3(0, 0.4, 0), Vec3(0.4, 0, 0),
                                Vec3(5, 5, 5), false, kPi));
}
void world_emitters(Scene& s) {
    s.add_light(make_world_light(Vec3(0.3, 0.4, 0.5)));
    add_emissive_sphere(s, Vec3(0.3, 0.2, 0.7), 0.25, 6, 12, Vec3(3, 2, 1));
}
void mesh_light(Scene& s) { add_emissive_sphere(s, Vec3(0.2, 0.1, 0.6), 0.3, 16, 32, Vec3(3, 2.5, 2)); }
void many_area_lights(Scene& s) {
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j)
            s.add_light(make_rect_light(Vec3(-1 + 0.2 * i, -1 + 0.2 * j, 0.9 + 0.02 * (i % 3)),
                                        Vec3(0, 0.05, 0), Vec3(0.05, 0, 0),
                                        Vec3(1 + i, 1 + j, 2), false, kPi));
}

struct BakeJob {
    std::string name;
    std::function<void(Scene&)> lights;
    bool mesh_lights = true;
    std::function<void(BakeSettings&)> settings;
};

void hash_bake(Hash& h, const BakeResult& r) {
    h.values(r.value);
    h.values(r.noise);
    h.values(r.mask);
    h.values(r.samples);
    const BakeStats& s = r.stats;
    h.value(int(s.status));
    for (auto v : {s.samples, s.draws, s.rays_traced, s.mis_systems}) h.value(v);
    h.value(s.shadowed_texels);
    h.value(s.passes);
    h.value(s.passes_per_texel);
    h.value(s.mean_relative_error);
    h.value(s.max_relative_error);
    h.values(s.samples_per_round);
    h.values(s.allocated_shares);
    h.bytes(s.plan.data(), s.plan.size());
    h.bytes(s.allocation.data(), s.allocation.size());
    for (const auto& t : s.techniques) h.bytes(t.data(), t.size());
}

std::uint64_t run_bake(const BakeJob& job) {
    Scene scene;
    Floor f;
    scene.set_mesh_lights(job.mesh_lights);
    floor_scene(scene, f, job.lights);
    scene.commit();
    BakeSettings b;
    b.width = b.height = 24;
    b.margin = 2;
    b.threads = 2;
    b.lighting.seed = 7;
    b.lighting.rounds = 16;
    job.settings(b);
    Hash h;
    const BakeResult r = bake(scene, b);
    if (std::getenv("OMIS_HASHES_VERBOSE"))
        std::fprintf(stderr, "  covered %zu samples %llu passes %d plan %s\n", r.stats.covered,
                     (unsigned long long)r.stats.samples, r.stats.passes, r.stats.plan.c_str());
    hash_bake(h, r);
    return h.h;
}

void techniques(BakeSettings& b, const std::vector<std::string>& names, int samples = 1) {
    b.lighting = lighting_settings(names, std::vector<int>(names.size(), samples),
                                   b.lighting.rounds, b.lighting.strategy, b.lighting.seed);
}

std::vector<BakeJob> bake_jobs() {
    std::vector<BakeJob> jobs;
    const Strategy strategies[] = {Strategy::Balance, Strategy::OptimalDirect,
                                   Strategy::OptimalProgressive, Strategy::Power};
    const struct {
        const char* name;
        std::function<void(Scene&)> lights;
        bool mesh_lights;
    } scenes[] = {{"rects", rect_lights, true},          {"spread", spread_lights, true},
                  {"delta", delta_lights, true},         {"many_delta", many_delta_lights, true},
                  {"world", world_lights, true},         {"world_emitters", world_emitters, true},
                  {"mesh_light", mesh_light, true},      {"triangles", mesh_light, false},
                  {"many_area", many_area_lights, true}};
    for (const auto& sc : scenes)
        for (Strategy st : strategies)
            jobs.push_back({std::string("bake ") + sc.name + " " + strategy_name(st), sc.lights,
                            sc.mesh_lights, [st](BakeSettings& b) { b.lighting.strategy = st; }});
    // Options, on the scenes they matter for.
    jobs.push_back({"bake rects streams=4 samples=37", rect_lights, true, [](BakeSettings& b) {
                        b.lighting.streams = 4;
                        b.samples = 37;
                    }});
    jobs.push_back({"bake rects shadowed_draws=4", rect_lights, true,
                    [](BakeSettings& b) { b.lighting.shadowed_draws = 4; }});
    jobs.push_back({"bake triangles general path", mesh_light, false,
                    [](BakeSettings& b) { b.lighting.fast_paths = false; }});
    jobs.push_back({"bake world_emitters general path", world_emitters, true,
                    [](BakeSettings& b) { b.lighting.fast_paths = false; }});
    jobs.push_back({"bake rects noise target", rect_lights, true, [](BakeSettings& b) {
                        b.noise_target = 0.02;
                        b.lighting.rounds = 64;
                        b.rounds_per_pass = 2;
                        b.lighting.streams = 2;
                    }});
    jobs.push_back({"bake spread noise target optimal-progressive", spread_lights, true,
                    [](BakeSettings& b) {
                        b.noise_target = 0.03;
                        b.lighting.rounds = 32;
                        b.lighting.strategy = Strategy::OptimalProgressive;
                    }});
    jobs.push_back({"bake rects allocation", rect_lights, true, [](BakeSettings& b) {
                        b.allocate_samples = true;
                        b.lighting.strategy = Strategy::OptimalDirect;
                        b.samples = 24;
                    }});
    jobs.push_back({"bake many_area allocation noise", many_area_lights, true,
                    [](BakeSettings& b) {
                        b.allocate_samples = true;
                        b.lighting.strategy = Strategy::OptimalDirect;
                        b.noise_target = 0.05;
                        b.lighting.rounds = 16;
                    }});
    jobs.push_back({"bake vertices", spread_lights, true, [](BakeSettings& b) {
                        b.target = BakeTarget::Vertices;
                    }});
    jobs.push_back({"bake corners delta", delta_lights, true, [](BakeSettings& b) {
                        b.target = BakeTarget::Corners;
                    }});
    const std::vector<std::vector<std::string>> sets = {
        {"bsdf", "uniform/area"},
        {"bsdf", "power/solid-angle", "unoccluded/parallel"},
        {"uniform/projected-solid-angle", "defensive/solid-angle"},
        {"bsdf", "tree/solid-angle", "tree/area"},
        {"unoccluded/solid-angle", "defensive/parallel", "power/area"},
    };
    for (const auto& set : sets) {
        std::string n;
        for (const auto& t : set) n += " " + t;
        for (Strategy st : {Strategy::Balance, Strategy::OptimalDirect}) {
            jobs.push_back({"bake spread" + n + " " + strategy_name(st), spread_lights, true,
                            [set, st](BakeSettings& b) {
                                b.lighting.strategy = st;
                                techniques(b, set, 2);
                            }});
            jobs.push_back({"bake many_area" + n + " " + strategy_name(st), many_area_lights,
                            true, [set, st](BakeSettings& b) {
                                b.lighting.strategy = st;
                                techniques(b, set);
                            }});
            jobs.push_back({"bake world" + n + " " + strategy_name(st), world_lights, true,
                            [set, st](BakeSettings& b) {
                                b.lighting.strategy = st;
                                techniques(b, set);
                            }});
        }
    }
    return jobs;
}

// direct_lighting() at points of the floor, with the variance and counters.
std::uint64_t run_points(const std::function<void(Scene&)>& lights, Strategy strategy,
                         int streams) {
    Scene scene;
    Floor f;
    floor_scene(scene, f, lights);
    scene.commit();
    std::vector<double> p, n;
    for (int i = 0; i < 40; ++i) {
        p.insert(p.end(), {-0.95 + 0.047 * i, 0.8 * std::sin(0.7 * i), 0});
        n.insert(n.end(), {0, 0, 1});
    }
    DirectLightingSettings s;
    default_techniques(scene, s.techniques, s.samples);
    s.rounds = 6;
    s.strategy = strategy;
    s.streams = streams;
    s.seed = 11;
    std::vector<double> value(p.size()), variance(p.size());
    const DirectLightingStats st =
        direct_lighting(scene, p.data(), n.data(), p.size() / 3, s, value.data(), variance.data());
    Hash h;
    h.values(value);
    h.values(variance);
    for (auto v : {st.points, st.samples, st.rays_traced, st.mis_systems, st.pdf_evaluations})
        h.value(v);
    return h.h;
}

// One PointLighting over the points with a counting keep_going: the polling
// cadence.
std::uint64_t run_polls() {
    Scene scene;
    Floor f;
    floor_scene(scene, f, spread_lights);
    scene.commit();
    DirectLightingSettings s;
    default_techniques(scene, s.techniques, s.samples);
    for (int& c : s.samples) c *= 37;
    s.rounds = 5;
    s.seed = 3;
    LightingContext context(scene, s);
    std::uint64_t polls = 0;
    context.keep_going = [&polls] {
        ++polls;
        return true;
    };
    PointLighting shading(context);
    Hash h;
    for (int i = 0; i < 12; ++i) {
        double value[3], variance[3];
        shading.shade(i, 0, 5, Vec3(-0.9 + 0.15 * i, 0.1, 0), Vec3(0, 0, 1), Vec3(0, 0, 1), value,
                      variance);
        h.value(value);
        h.value(variance);
        h.value(polls);
    }
    h.value(shading.counters);
    return h.h;
}

}  // namespace

int main(int argc, char** argv) {
    const char* only = argc > 1 ? argv[1] : "";
    Hash all;
    auto report = [&](const std::string& name, const std::function<std::uint64_t()>& run) {
        if (!std::strstr(name.c_str(), only)) return;
        const std::uint64_t h = run();
        all.value(h);
        std::printf("%016" PRIx64 "  %s\n", h, name.c_str());
        std::fflush(stdout);
    };
    for (const BakeJob& job : bake_jobs()) report(job.name, [&] { return run_bake(job); });
    for (Strategy st : {Strategy::Balance, Strategy::OptimalDirect, Strategy::OptimalProgressive})
        for (int streams : {1, 3}) {
            const std::string name =
                std::string("points ") + strategy_name(st) + " streams=" + std::to_string(streams);
            report(name + " spread", [&] { return run_points(spread_lights, st, streams); });
            report(name + " delta", [&] { return run_points(delta_lights, st, streams); });
            report(name + " world", [&] { return run_points(world_lights, st, streams); });
        }
    report("polls spread", run_polls);
    for (const hard_cases::HardCase& hc : hard_cases::suite())
        for (Strategy st : {Strategy::Balance, Strategy::OptimalDirect, Strategy::OptimalProgressive})
            report("hard case " + hc.name + " " + strategy_name(st), [&] {
                Scene scene;
                hc.build(scene);
                scene.commit();
                Hash h;
                h.values(hard_cases::run(scene, hc, st, 4, 3, 5));
                return h.h;
            });
    std::printf("%016" PRIx64 "  all\n", all.h);
}
