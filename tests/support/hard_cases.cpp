#include "support/hard_cases.h"

#include <algorithm>
#include <ctime>
#include <cmath>

#include "mis/allocation.h"
#include "render/direct_lighting.h"
#include "render/techniques.h"

namespace omis::hard_cases {
namespace {

const std::vector<std::string> kThree = {"bsdf", "power/solid-angle", "uniform/area"};

std::vector<std::string> all_ten() {
    std::vector<std::string> names = {"bsdf"};
    for (const char* selection : {"uniform", "power", "unoccluded"})
        for (const char* sampler : {"area", "solid-angle", "parallel"})
            names.push_back(std::string(selection) + "/" + sampler);
    return names;
}

// A two-triangle quad corner, corner+u, corner+u+v, corner+v.
void add_quad(Scene& scene, const Vec3& corner, const Vec3& u, const Vec3& v,
              std::optional<Vec3> emission = std::nullopt) {
    scene.add_mesh({corner, corner + u, corner + u + v, corner + v}, {{{0, 1, 2}}, {{0, 2, 3}}},
                   emission);
}

// `count` points evenly on the segment [from, to], all with normal n.
void add_row(HardCase& c, const Vec3& from, const Vec3& to, const Vec3& n, int count) {
    for (int i = 0; i < count; ++i) {
        const double t = count > 1 ? double(i) / (count - 1) : 0.5;
        c.points.push_back(from + (to - from) * t);
        c.normals.push_back(n);
    }
}

// A wall (x = 0, facing +x) lit at grazing angles from above by a downward
// disk with a 60° spread and from below by a dim emissive floor strip.
void build_grazing(Scene& scene) {
    scene.add_light(make_ellipse_light(Vec3(0.25, 0, 2.0), Vec3(0, 0.3, 0), Vec3(0.3, 0, 0),
                                       Vec3(20, 16, 12), false, kPi / 3));
    add_quad(scene, Vec3(0.05, -1, 0), Vec3(1, 0, 0), Vec3(0, 2, 0), Vec3(0.3, 0.4, 0.5));
}

HardCase grazing(std::vector<std::string> techniques, std::string name) {
    HardCase c{std::move(name), build_grazing, {}, {}, std::move(techniques)};
    add_row(c, Vec3(0, -0.9, 0.1), Vec3(0, 0.9, 1.8), Vec3(1, 0, 0), 8);
    return c;
}

}  // namespace

std::vector<HardCase> suite() {
    std::vector<HardCase> cases;
    cases.push_back(grazing(kThree, "grazing disk + emissive plane"));
    cases.push_back(grazing(all_ten(), "all ten techniques"));

    HardCase tiny{"tiny bright beside large dim", nullptr, {}, {}, kThree};
    // Downward-facing lights: edges chosen so cross(u, v) points to −z.
    tiny.build = [](Scene& s) {
        s.add_light(make_rect_light(Vec3(0.3, -0.01, 1.0), Vec3(0, 0.02, 0), Vec3(0.02, 0, 0),
                                    Vec3(2e4, 2e4, 2e4), false, kPi));
        s.add_light(make_rect_light(Vec3(-2, -1, 1.5), Vec3(0, 2, 0), Vec3(2, 0, 0),
                                    Vec3(0.5, 0.5, 0.6), false, kPi));
    };
    add_row(tiny, Vec3(-1, 0.2, 0), Vec3(1.2, -0.2, 0), Vec3(0, 0, 1), 8);
    cases.push_back(tiny);

    HardCase horizon{"light partly below the horizon",
                     [](Scene& s) {
                         // Vertical rect at x = 1 facing −x, from z = −0.5 to 1.
                         s.add_light(make_rect_light(Vec3(1, -0.5, -0.5), Vec3(0, 0, 1.5),
                                                     Vec3(0, 1, 0), Vec3(5, 5, 5), false, kPi));
                     },
                     {}, {}, kThree};
    add_row(horizon, Vec3(-1, 0, 0), Vec3(0.9, 0.3, 0), Vec3(0, 0, 1), 8);
    cases.push_back(horizon);

    HardCase penumbra{"penumbra",
                      [](Scene& s) {
                          s.add_light(make_rect_light(Vec3(-0.5, -0.5, 2), Vec3(0, 1, 0),
                                                      Vec3(1, 0, 0), Vec3(4, 4, 4), false, kPi));
                          // Occluder: the half-plane x < 0 at height 1.
                          add_quad(s, Vec3(-3, -3, 1), Vec3(0, 6, 0), Vec3(3, 0, 0));
                      },
                      {}, {}, kThree};
    add_row(penumbra, Vec3(-1, 0, 0), Vec3(1, 0.1, 0), Vec3(0, 0, 1), 8);
    cases.push_back(penumbra);

    HardCase corner{"dim corner",
                    [](Scene& s) {
                        // Walls x = 0 and y = 0 (occluders); a ceiling light in the
                        // far corner with a 117° spread, so the corner is at its edge.
                        add_quad(s, Vec3(0, 0, 0), Vec3(0, 4, 0), Vec3(0, 0, 3));
                        add_quad(s, Vec3(0, 0, 0), Vec3(0, 0, 3), Vec3(4, 0, 0));
                        s.add_light(make_rect_light(Vec3(2.5, 2.5, 2.8), Vec3(0, 1, 0),
                                                    Vec3(1, 0, 0), Vec3(6, 6, 5), false,
                                                    0.65 * kPi));
                    },
                    {}, {}, kThree};
    add_row(corner, Vec3(0.02, 0.02, 0), Vec3(0.6, 0.3, 0), Vec3(0, 0, 1), 8);
    cases.push_back(corner);
    return cases;
}

std::vector<double> run(const Scene& scene, const HardCase& hard_case, Strategy strategy,
                        int spp, int copies, std::uint64_t seed) {
    return run_counts(scene, hard_case, strategy,
                      std::vector<int>(hard_case.techniques.size(), 1), spp, copies, seed);
}

std::vector<double> run_counts(const Scene& scene, const HardCase& hard_case, Strategy strategy,
                               const std::vector<int>& counts, int rounds, int copies,
                               std::uint64_t seed) {
    DirectLightingSettings s;
    for (const auto& name : hard_case.techniques) s.techniques.push_back(*parse_technique(name));
    s.samples = counts;
    s.rounds = rounds;
    s.strategy = strategy;
    s.seed = seed;
    std::vector<double> points, normals;
    for (std::size_t p = 0; p < hard_case.points.size(); ++p)
        for (int k = 0; k < copies; ++k) {
            const Vec3 &x = hard_case.points[p], &n = hard_case.normals[p];
            points.insert(points.end(), {x.x, x.y, x.z});
            normals.insert(normals.end(), {n.x, n.y, n.z});
        }
    const std::size_t count = points.size() / 3;
    std::vector<double> value(3 * count), variance(3 * count);
    direct_lighting(scene, points.data(), normals.data(), count, s, value.data(),
                    variance.data());
    return value;
}

namespace {

// Rounds of the allocated call: the fewest settings rounds per allocated round
// that hold at least 8 samples, 4 a technique, and divide the rounds left (as
// the baker; here one sample per technique a round).
int allocated_rounds(int rounds_left, int per_round) {
    const int least = std::max(8, 4 * per_round);
    for (int g = 1; g <= rounds_left; ++g)
        if (rounds_left % g == 0 && g * per_round >= least) return rounds_left / g;
    return 1;
}

}  // namespace

AllocatedRun run_allocated(const Scene& scene, const HardCase& hard_case, Strategy strategy,
                           int spp, int pilot_rounds, int copies, std::uint64_t seed,
                           bool choose, double floor) {
    DirectLightingSettings s;
    for (const auto& name : hard_case.techniques) s.techniques.push_back(*parse_technique(name));
    const int T = int(s.techniques.size());
    s.samples.assign(T, 1);
    s.rounds = spp;
    s.strategy = strategy;
    s.seed = seed;
    const LightingContext context(scene, s);
    PointLighting shader(context);
    const int points = int(hard_case.points.size());
    AllocatedRun out;
    out.values.assign(std::size_t(points) * copies * 3, 0.0);
    out.shares.assign(T, 0.0);
    // CPU time of this thread: the shared machine's load does not enter it.
    auto cpu_seconds = [] {
        timespec t;
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
        return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
    };
    const double start = cpu_seconds();
    for (int k = 0; k < copies; ++k) {
        auto shade = [&](int p, int first, int rounds, const int* counts,
                         const std::vector<DrawnRounds>* earlier, double* value) {
            const Vec3 &x = hard_case.points[p], &n = hard_case.normals[p];
            shader.shade(std::uint64_t(p) * copies + k, first, rounds, SurfacePoint{x, n, n},
                         nullptr, value, nullptr, counts, nullptr, nullptr, earlier);
        };
        if (pilot_rounds <= 0 || pilot_rounds >= spp) {
            for (int p = 0; p < points; ++p)
                shade(p, 0, spp, nullptr, nullptr, &out.values[(std::size_t(p) * copies + k) * 3]);
            continue;
        }
        AllocationPilot pilot(T, 1, s.samples);
        std::vector<double> first(std::size_t(points) * 3);
        shader.record_into(&pilot);
        for (int p = 0; p < points; ++p) {
            double* v = &first[std::size_t(p) * 3];
            shade(p, 0, pilot_rounds, nullptr, nullptr, v);
            const double y = luminance(Vec3(v[0], v[1], v[2]));
            pilot.end_point(y > 0 ? 1 / y : 0.0, pilot_rounds);
        }
        shader.record_into(nullptr);
        const std::vector<double> shares =
            choose ? optimal_shares(pilot, pilot.cost(), floor) : std::vector<double>(T, 1.0 / T);
        for (int t = 0; t < T; ++t) out.shares[t] += shares[t] / copies;
        const int left = spp - pilot_rounds;
        const int rounds = allocated_rounds(left, T);
        const std::vector<int> counts = counts_from_shares(shares, left * T / rounds);
        const std::vector<DrawnRounds> earlier = {{0, pilot_rounds, nullptr}};
        const double w = double(pilot_rounds) / spp;
        for (int p = 0; p < points; ++p) {
            double second[3];
            shade(p, pilot_rounds, rounds, counts.data(), &earlier, second);
            double* v = &out.values[(std::size_t(p) * copies + k) * 3];
            for (int c = 0; c < 3; ++c) v[c] = w * first[std::size_t(p) * 3 + c] + (1 - w) * second[c];
        }
    }
    out.seconds = cpu_seconds() - start;
    return out;
}

std::vector<double> reference(const Scene& scene, const HardCase& hard_case, int rounds,
                              int copies, std::uint64_t seed) {
    const std::vector<double> values = run(scene, hard_case, Strategy::Balance, rounds, copies,
                                           seed);
    const std::size_t points = hard_case.points.size();
    std::vector<double> ref(3 * points, 0.0);
    for (std::size_t p = 0; p < points; ++p)
        for (int k = 0; k < copies; ++k)
            for (int c = 0; c < 3; ++c) ref[3 * p + c] += values[(p * copies + k) * 3 + c] / copies;
    return ref;
}

Errors errors(const std::vector<double>& values, const std::vector<double>& ref, int points,
              int copies) {
    // Each point's errors are scaled by its reference luminance, floored at a
    // tenth of the case's mean so dark points do not dominate.
    std::vector<double> scale(points);
    double mean_luminance = 0;
    for (int p = 0; p < points; ++p) {
        scale[p] = (ref[3 * p] + ref[3 * p + 1] + ref[3 * p + 2]) / 3;
        mean_luminance += scale[p] / points;
    }
    for (double& s : scale) s = 1.0 / std::max(s, 0.1 * mean_luminance);

    Errors e;
    e.squared.assign(std::size_t(points) * copies, 0.0);
    for (int p = 0; p < points; ++p) {
        for (int c = 0; c < 3; ++c) {
            double mean = 0, m2 = 0;
            for (int k = 0; k < copies; ++k) {
                const double d = (values[(p * copies + k) * 3 + c] - ref[3 * p + c]) * scale[p];
                e.squared[p * copies + k] += d * d;
                mean += d / copies;
            }
            for (int k = 0; k < copies; ++k) {
                const double d = (values[(p * copies + k) * 3 + c] - ref[3 * p + c]) * scale[p];
                m2 += (d - mean) * (d - mean) / (copies - 1);
            }
            e.bias.push_back(mean);
            e.sigma.push_back(std::sqrt(m2));
        }
        const bool lit = ref[3 * p] + ref[3 * p + 1] + ref[3 * p + 2] > 0;
        for (int k = 0; k < copies; ++k) {
            const double* v = &values[(p * copies + k) * 3];
            if (v[0] < 0 || v[1] < 0 || v[2] < 0) ++e.negative;
            if (lit && v[0] == 0 && v[1] == 0 && v[2] == 0) ++e.zero;
        }
    }
    for (double s : e.squared) e.mse += s / e.squared.size();
    return e;
}

double bias_over_sigma(const Errors& e, const Errors& balance) {
    double sum = 0;
    int terms = 0;
    for (std::size_t i = 0; i < e.bias.size(); ++i)
        if (balance.sigma[i] > 0) {
            sum += (e.bias[i] / balance.sigma[i]) * (e.bias[i] / balance.sigma[i]);
            ++terms;
        }
    return terms ? std::sqrt(sum / terms) : 0.0;
}

}  // namespace omis::hard_cases
