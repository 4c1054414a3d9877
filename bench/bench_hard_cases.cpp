// The hard-case suite of issue 10 (tests/hard_cases): per case and sample
// count, the MSE of optimal-direct and optimal-progressive relative to the
// balance heuristic, negative and zero texel counts, and bias/σ.
//   omis_bench_hard_cases [copies] [reference rounds] [case name part] [spp,...] [per round]
// (per round: samples of each technique per round, 1 by default, so spp = rounds)
//   omis_bench_hard_cases --cost STRATEGY SPP TEXELS   (see cost_run)
//   omis_bench_hard_cases --allocation COPIES          (see allocation_sweep)
//   omis_bench_hard_cases --allocation-gain COPIES [spp,...]  (see allocation_gain)
// Errors are against a balance reference of `reference rounds` rounds over 16
// copies; bias/σ is the rms over points of (mean error)/(σ of one balance
// estimate at that spp), whose noise floor for an unbiased strategy is about
// 1/√copies.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "support/hard_cases.h"

using namespace omis;
using namespace omis::hard_cases;

// --cost STRATEGY SPP TEXELS: shade the first case's wall with its first two
// techniques at SPP rounds (2·SPP samples per texel) and nothing else, for
// instruction counts under callgrind (repeatable on a shared machine):
// (Ir(optimal) − Ir(balance)) / (Ir(balance) − Ir(TEXELS = 0)) is optimal's
// cost per sample over balance.
int cost_run(const char* strategy_name_arg, int spp, int texels) {
    const auto strategy = parse_strategy(strategy_name_arg);
    if (!strategy || spp < 1 || texels < 0) {
        std::fprintf(stderr, "--cost: need a strategy name, spp ≥ 1, texels ≥ 0\n");
        return 2;
    }
    HardCase hc = suite()[0];
    hc.techniques.resize(2);
    Scene scene;
    hc.build(scene);
    scene.commit();
    // Texels spread over the wall so no two share a position.
    const HardCase row = hc;
    hc.points.clear();
    hc.normals.clear();
    for (int i = 0; i < texels; ++i) {
        const double t = (i + 0.5) / texels;
        hc.points.push_back(Vec3(0, -0.9 + 1.8 * t, 0.1 + 1.7 * std::fmod(7.31 * t, 1.0)));
        hc.normals.push_back(row.normals[0]);
    }
    const std::vector<double> v = run(scene, hc, *strategy, spp, 1, 42);
    double sum = 0;
    for (double x : v) sum += x;
    std::printf("%s spp %d texels %d: mean %.6g\n", strategy_name(*strategy), spp, texels,
                texels ? sum / (3 * texels) : 0.0);
    return 0;
}

// --allocation: the most any fixed allocation could gain over equal counts
// (issue 10, item 2), at equal samples: per three-technique case,
// optimal-direct's MSE with every count vector of 4 samples per round
// (12 rounds) relative to 1 sample each (16 rounds), both 48 samples a point.
int allocation_sweep(int copies) {
    const std::vector<std::vector<int>> allocations = {
        {1, 1, 1}, {2, 1, 1}, {1, 2, 1}, {1, 1, 2}};
    std::printf("equal samples (48 per point): optimal-direct MSE relative to counts 1,1,1 "
                "(± 1 standard error of the paired ratio)\n");
    for (const HardCase& hc : suite()) {
        if (hc.techniques.size() != 3) continue;
        Scene scene;
        hc.build(scene);
        scene.commit();
        const int points = int(hc.points.size());
        const auto ref = reference(scene, hc, 4096, 16, 987654321);
        std::printf("  %-34s", hc.name.c_str());
        Errors equal;
        for (const auto& counts : allocations) {
            const int rounds = counts == allocations[0] ? 16 : 12;
            const Errors e = errors(run_counts(scene, hc, Strategy::OptimalDirect, counts, rounds,
                                               copies, 42),
                                    ref, points, copies);
            if (counts == allocations[0]) {
                equal = e;
                continue;
            }
            const double ratio = e.mse / equal.mse;
            double var = 0;
            for (std::size_t i = 0; i < e.squared.size(); ++i) {
                const double d = e.squared[i] - ratio * equal.squared[i];
                var += d * d / (e.squared.size() - 1);
            }
            std::printf("  %d,%d,%d: %5.3f ± %5.3f", counts[0], counts[1], counts[2], ratio,
                        std::sqrt(var / e.squared.size()) / equal.mse);
        }
        std::printf("\n");
    }
    return 0;
}

// --allocation-gain COPIES [spp,...]: sample allocation (issue 10, item 2)
// against fixed counts at equal samples, per case and spp: optimal-direct's
// MSE with allocation (a quarter of the rounds as the pilot, the copy's 8
// points as the tile) over its MSE with one sample per technique per round,
// (and over the same pilot and later call keeping one sample per technique
// a round: the choice alone), the shading-time ratio of allocation to fixed
// counts (serial, one run, the least of three), and their product —
// the ratio of variance at equal time (< 1: allocation wins).
int allocation_gain(int copies, const std::vector<int>& spps) {
    std::printf("sample allocation vs fixed counts, optimal-direct, %d copies of 8 points\n"
                "  MSE ratio (± 1 standard error of the paired ratio), time ratio, "
                "MSE×time ratio, mean shares\n", copies);
    double log_sum = 0;
    int cells = 0;
    for (const HardCase& hc : suite()) {
        Scene scene;
        hc.build(scene);
        scene.commit();
        const int points = int(hc.points.size());
        const auto ref = reference(scene, hc, 4096, 16, 987654321);
        std::printf("%s (%zu techniques)\n", hc.name.c_str(), hc.techniques.size());
        for (int spp : spps) {
            // Three interleaved repetitions (the same values), the least time
            // of each: a burst of load on the shared machine hits one, not all.
            AllocatedRun fixed, kept, alloc;
            for (int rep = 0; rep < 3; ++rep) {
                const AllocatedRun f =
                    run_allocated(scene, hc, Strategy::OptimalDirect, spp, 0, copies, 42);
                const AllocatedRun k = run_allocated(scene, hc, Strategy::OptimalDirect, spp,
                                                     spp / 4, copies, 42, false);
                const AllocatedRun a =
                    run_allocated(scene, hc, Strategy::OptimalDirect, spp, spp / 4, copies, 42);
                if (rep == 0 || f.seconds < fixed.seconds) fixed = f;
                if (rep == 0 || k.seconds < kept.seconds) kept = k;
                if (rep == 0 || a.seconds < alloc.seconds) alloc = a;
            }
            const Errors e_fixed = errors(fixed.values, ref, points, copies);
            const Errors e_kept = errors(kept.values, ref, points, copies);
            const Errors e_alloc = errors(alloc.values, ref, points, copies);
            auto paired = [](const Errors& x, const Errors& y, double& se) {
                const double ratio = x.mse / y.mse;
                double var = 0;
                for (std::size_t i = 0; i < x.squared.size(); ++i) {
                    const double d = x.squared[i] - ratio * y.squared[i];
                    var += d * d / (x.squared.size() - 1);
                }
                se = std::sqrt(var / x.squared.size()) / y.mse;
                return ratio;
            };
            double se, se_kept;
            const double ratio = paired(e_alloc, e_fixed, se);
            const double ratio_kept = paired(e_alloc, e_kept, se_kept);
            const double time = alloc.seconds / fixed.seconds;
            std::printf("  %4d spp: MSE %6.3f ± %5.3f (vs kept %6.3f ± %5.3f)  time %5.3f "
                        "(kept %5.3f)  MSE×time %6.3f  shares", spp, ratio, se, ratio_kept,
                        se_kept, time, kept.seconds / fixed.seconds, ratio * time);
            for (double w : alloc.shares) std::printf(" %.2f", w);
            std::printf("\n");
            log_sum += std::log(ratio * time);
            ++cells;
        }
    }
    std::printf("geometric mean MSE×time ratio: %.3f over %d cells\n",
                std::exp(log_sum / std::max(1, cells)), cells);
    return 0;
}

std::vector<int> parse_counts(const char* list) {
    std::vector<int> counts;
    for (const char* p = list; *p;) {
        char* end;
        counts.push_back(int(std::strtol(p, &end, 10)));
        p = *end ? end + 1 : end;
    }
    return counts;
}

int main(int argc, char** argv) {
    if (argc >= 3 && std::string(argv[1]) == "--allocation-gain")
        return allocation_gain(std::atoi(argv[2]),
                               parse_counts(argc > 3 ? argv[3] : "4,16,64,256"));
    if (argc == 3 && std::string(argv[1]) == "--allocation")
        return allocation_sweep(std::atoi(argv[2]));
    if (argc == 5 && std::string(argv[1]) == "--cost")
        return cost_run(argv[2], std::atoi(argv[3]), std::atoi(argv[4]));
    const int copies = argc > 1 ? std::atoi(argv[1]) : 64;
    const int reference_rounds = argc > 2 ? std::atoi(argv[2]) : 4096;
    const std::string only = argc > 3 ? argv[3] : "";  // cases whose name holds this
    std::vector<int> counts = {1, 4, 16, 64, 256};
    if (argc > 4) counts = parse_counts(argv[4]);
    const int per_round = argc > 5 ? std::atoi(argv[5]) : 1;  // samples a technique a round
    if (copies < 2 || reference_rounds < 1 ||
        std::any_of(counts.begin(), counts.end(), [](int n) { return n < 1; }) ||
        per_round < 1) {
        std::fprintf(stderr,
                     "usage: %s [copies ≥ 2] [reference rounds ≥ 1] [case name part] "
                     "[rounds,rounds,...] [samples per technique per round]\n",
                     argv[0]);
        return 2;
    }
    const Strategy strategies[3] = {Strategy::Balance, Strategy::OptimalDirect,
                                    Strategy::OptimalProgressive};
    std::printf("hard cases: %d copies of 8 points per case, %d sample(s) per technique a round; "
                "the first column counts rounds\n"
                "MSE ratios to balance (± 1 standard error of the paired ratio);"
                " neg/zero texels and bias/σ as bal/dir/prog\n\n", copies, per_round);
    double worst[2] = {0, 0};
    for (const HardCase& hc : suite()) {
        if (hc.name.find(only) == std::string::npos) continue;
        Scene scene;
        hc.build(scene);
        scene.commit();
        const int points = int(hc.points.size());
        const auto ref = reference(scene, hc, reference_rounds, 16, 987654321);
        std::printf("%s (%zu techniques)\n", hc.name.c_str(), hc.techniques.size());
        std::printf("  %5s %17s %17s %11s %11s %17s\n", "spp", "direct/balance",
                    "progr/balance", "negative", "zero", "bias/σ");
        for (int spp : counts) {
            Errors e[3];
            for (int s = 0; s < 3; ++s)
                e[s] = errors(run_counts(scene, hc, strategies[s],
                                         std::vector<int>(hc.techniques.size(), per_round), spp,
                                         copies, 42),
                              ref, points, copies);
            double ratio[2], se[2];
            for (int s = 0; s < 2; ++s) {
                // Delta method for the ratio of two paired means.
                const auto& x = e[s + 1].squared;
                const auto& y = e[0].squared;
                ratio[s] = e[s + 1].mse / e[0].mse;
                double var = 0;
                for (std::size_t i = 0; i < x.size(); ++i) {
                    const double d = x[i] - ratio[s] * y[i];
                    var += d * d / (x.size() - 1);
                }
                se[s] = std::sqrt(var / x.size()) / e[0].mse;
                worst[s] = std::max(worst[s], ratio[s]);
            }
            std::printf("  %5d %9.3f ± %5.3f %9.3f ± %5.3f %3d/%3d/%3d %3d/%3d/%3d %5.2f/%5.2f/%5.2f\n",
                        spp, ratio[0], se[0], ratio[1], se[1], e[0].negative, e[1].negative,
                        e[2].negative, e[0].zero, e[1].zero, e[2].zero, bias_over_sigma(e[0], e[0]),
                        bias_over_sigma(e[1], e[0]), bias_over_sigma(e[2], e[0]));
        }
        std::printf("\n");
    }
    std::printf("worst MSE ratio to balance: optimal-direct %.3f, optimal-progressive %.3f\n",
                worst[0], worst[1]);
    return 0;
}
