// Streaming MIS estimator for N techniques and C channels (SPEC §1–§2).
//
// Samples arrive one by one or in batches, ordered round by round (each round
// holds counts[k] samples of technique k, in any order inside the round).
// Memory is O(N² + N·C) whatever the sample count; sums are in double.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "mis/strategy.h"

namespace omis {

constexpr int kMaxMisTechniques = 32;
constexpr int kMaxMisChannels = 4;

struct MisResult {
    std::vector<double> estimate;  // per channel
    std::vector<double> variance;  // per channel: estimated variance of the estimate
    int rounds = 0;
    int rank = 0;  // optimal strategies: techniques kept by the last solve
    // Optimal strategies: bit c set when channel c's estimate left the range
    // the samples allow and the balance estimate was returned instead.
    int fell_back = 0;
};

// optimal-direct falls back to the balance estimate when it differs from it
// by more than this many of balance's own standard errors. The true
// difference is the control variate's error, whose σ is at most balance's
// (V_bal = V_opt + V[G_bal]); 4σ is beyond any honest correction, so the
// rule fires on broken few-sample solves, not on real gains.
constexpr double kDirectFallbackSigmas = 4.0;

class MisEstimator {
public:
    // Throws std::invalid_argument when counts or sizes are unusable.
    MisEstimator(Strategy strategy, int num_techniques, int num_channels,
                 const std::vector<int>& counts, StrategyOptions options = {});

    // One sample drawn by `technique`: pdfs[k] = p_k(x) for every technique k,
    // f[c] = integrand. Throws std::invalid_argument on bad values or order.
    void add_sample(int technique, const double* pdfs, const double* f);

    // A draw of `technique` that produced no usable direction (a measure-zero
    // event such as a grazing degenerate sample): it counts toward the round
    // with f = 0 and no density, so it adds nothing to any sum.
    void add_null_sample(int technique);

    // Strided batch (strides in bytes); errors name the sample's index.
    void add_samples(size_t count, const int* technique, size_t technique_stride,
                     const double* pdfs, size_t pdf_stride, const double* f,
                     size_t f_stride);

    // The estimate over all complete rounds. Throws std::logic_error when a
    // round is incomplete or no round was added.
    MisResult result() const;

    // The control-variate estimate (SPEC §2) for a given α (N×C, [k*C + c]);
    // any α ∝ n reproduces the balance estimate bit for bit.
    std::vector<double> control_variate_estimate(const std::vector<double>& alpha) const;

    int num_techniques() const { return N_; }
    int num_channels() const { return C_; }
    int completed_rounds() const { return rounds_; }
    Strategy strategy() const { return strategy_; }
    void reset();

private:
    void finish_round();
    // Full symmetric Â, b̂, m̂ divided by R, in fixed storage (no allocation
    // per point); only the leading N×N, N×C and C entries are set.
    struct Moments {
        std::array<double, kMaxMisTechniques * kMaxMisTechniques> a;
        std::array<double, kMaxMisTechniques * kMaxMisChannels> b;
        std::array<double, kMaxMisChannels> m;
    };
    void normalized_moments(Moments& out) const;
    // Balance estimate plus the control-variate correction for α (N×C).
    double control_variate(const double* alpha, int c) const;
    double balance_estimate(int c) const;
    // The per-estimate guard (issue 10): a channel's optimal estimate is out of
    // range when it is negative although no sample had f < 0, or (sigmas > 0)
    // when it lies more than `sigmas` balance standard errors from balance.
    bool out_of_range(double estimate, int c, double sigmas, double balance_variance) const;
    // Σ_k β_k (1 − c_k/R) per channel with β = α less its inert n-component.
    double correction(const double* alpha, int c, const double* c_sums,
                      double rounds) const;

    Strategy strategy_;
    StrategyOptions options_;
    int N_, C_;
    std::vector<int> counts_;
    int samples_per_round_ = 0;
    double n_dot_n_ = 0;

    int rounds_ = 0;
    std::vector<int> in_round_;  // samples of each technique in the open round
    int round_left_ = 0;         // samples still missing from the open round

    // Per technique t, sums of Y = w_t f/(n_t p_t) and Y² (heuristics; for the
    // optimal strategies Y is the balance contribution f/q).
    std::vector<double> sum_y_, sum_y2_;
    std::vector<long long> seen_;  // samples per technique

    // Optimal strategies: Σ p_i p_j/q², Σ p_i f/q², Σ f²/q², Σ p_i/q, and the
    // accumulation kernel specialised for N and C.
    void (*moment_kernel_)(int, int, const double*, const double*, double*, double*,
                           double*, double*) = nullptr;
    std::vector<double> a_, b_, m_, c_;

    // Progressive: the running sums (a_, b_, m_, c_) after rounds 1, 2, 4,
    // 8, ..., one block each: the epoch boundaries of the cross-fit.
    std::vector<double> snapshots_;
    void progressive_estimate(MisResult& out) const;
    // Optimal strategies, per channel: whether any sample had f < 0.
    std::array<bool, kMaxMisChannels> negative_f_{};
};

}  // namespace omis
