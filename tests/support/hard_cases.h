// The hard-case suite of issue 10: scenes where optimal MIS used to lose to
// the balance heuristic (few samples, grazing light, very unequal emitters,
// lights below the horizon, penumbrae, dim corners). Shared by the test
// (tests/core/test_hard_cases.cpp) and the benchmark (bench/bench_hard_cases.cpp).
//
// A case is a scene, a row of receiver points and a technique set; a run
// lights `copies` independent copies of every point (each copy its own random
// stream) with one sample per technique per round, so spp = rounds.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "mis/strategy.h"
#include "render/scene.h"

namespace omis::hard_cases {

struct HardCase {
    std::string name;
    std::function<void(Scene&)> build;  // adds meshes and lights (not committed)
    std::vector<Vec3> points, normals;
    std::vector<std::string> techniques;
};

std::vector<HardCase> suite();

// RGB values of every (point, copy), point-major: [(p*copies + k)*3 + c].
std::vector<double> run(const Scene& scene, const HardCase& hard_case, Strategy strategy,
                        int spp, int copies, std::uint64_t seed);
// The same with `counts` samples per technique per round and `rounds` rounds.
std::vector<double> run_counts(const Scene& scene, const HardCase& hard_case, Strategy strategy,
                               const std::vector<int>& counts, int rounds, int copies,
                               std::uint64_t seed);

// Sample allocation (issue 10, item 2) as a bake does it, with the copy's 8
// points as the tile: `pilot_rounds` rounds of one sample per technique
// recorded into one pilot (each point's integrand scaled by 1/its estimate),
// shares from it (mis/allocation.h, floor `floor`), then the remaining
// spp − pilot_rounds rounds' samples in rounds of at least 8 (4 a technique)
// split by those shares; a point's value is the two calls' sample-weighted mean.
// pilot_rounds = 0: one call of spp rounds of one sample each (fixed counts).
// Serial; seconds: the shading's CPU time (the pilot's choice included). Same streams and
// layout as run().
struct AllocatedRun {
    std::vector<double> values;
    std::vector<double> shares;  // mean over copies
    double seconds = 0;
};
// choose = false: the same two calls, the later one keeping one sample per
// technique and round (what the allocation's choice is measured against).
AllocatedRun run_allocated(const Scene& scene, const HardCase& hard_case, Strategy strategy,
                           int spp, int pilot_rounds, int copies, std::uint64_t seed,
                           bool choose = true, double floor = 0.05);

// Per point and channel, the mean of `copies` balance runs of `rounds` rounds:
// the reference the errors are measured against.
std::vector<double> reference(const Scene& scene, const HardCase& hard_case, int rounds,
                              int copies, std::uint64_t seed);

// Errors of one strategy's run against the reference, every channel of every
// point scaled by the point's reference luminance (floored at a tenth of the
// case's mean), so that each point weighs alike.
struct Errors {
    std::vector<double> squared;  // per (point, copy): Σ_c scaled error², same order as run()
    double mse = 0;               // mean of `squared`
    std::vector<double> bias, sigma;  // per (point, channel): mean error, σ of one estimate
    int negative = 0;             // texels (point, copy) with a negative channel
    int zero = 0;                 // texels with every channel exactly 0 where the reference is not
};

Errors errors(const std::vector<double>& values, const std::vector<double>& reference,
              int points, int copies);

// rms over points and channels of the mean error of `e` divided by the σ of
// one balance estimate at the same sample count: how much a bias matters
// against the noise balance would leave. Its noise floor is ≈ 1/√copies (and
// the reference's error, far smaller).
double bias_over_sigma(const Errors& e, const Errors& balance);

}  // namespace omis::hard_cases
