// MIS combination strategies (SPEC §1–§2) and their options.
#pragma once

#include <cstdint>

#include <optional>
#include <string>
#include <string_view>

namespace omis {

enum class Strategy {
    Balance,
    Power,
    Maximum,
    Cutoff,
    OptimalDirect,       // solve once from all samples: biased, consistent
    // cross-fit: each epoch of rounds corrected with α from the others;
    // unbiased for independent rounds (with sequence_rounds, the level test's
    // small bias: mis/estimator.cpp)
    OptimalProgressive,
};

struct StrategyOptions {
    double beta = 2.0;    // exponent of the power heuristic
    double cutoff = 0.1;  // relative threshold a of the cutoff heuristic
    // Optimal strategies: round r holds point r of one scrambled Sobol'
    // sequence per technique (omis's own draws), not independent samples.
    // Then the correction is also judged by the sequence's own halves (the
    // level test, mis/estimator.cpp) — optimal-direct's α, and
    // optimal-progressive's cross-fitted corrections from 8 rounds on
    // (balance below) — since such draws err far less than the
    // independent-draw variances rule 3 compares.
    bool sequence_rounds = false;
    // Bit k: technique k's density reaches directions where f is surely 0
    // and where, rarely drawn, no sample may have landed (the bsdf technique
    // of a scene without a world: directions beside every light). An exact
    // fit that weighs such a density is not trusted (mis/estimator.cpp,
    // exact_fit; issue 32).
    std::uint32_t reaches_beyond_f = 0;
};

// Names are part of the interface (SPEC §6): "balance", "optimal-direct", ...
std::optional<Strategy> parse_strategy(std::string_view name);
const char* strategy_name(Strategy s);

// Weight w_t(x) of technique t under a heuristic strategy (SPEC §1), given
// every technique's pdf at x. Not defined for the optimal strategies.
double heuristic_weight(Strategy s, const StrategyOptions& options, int num_techniques,
                        const int* counts, const double* pdfs, int t);

inline bool is_optimal(Strategy s) {
    return s == Strategy::OptimalDirect || s == Strategy::OptimalProgressive;
}

}  // namespace omis
