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
    // optimal-direct: the α behind each channel's estimate less its inert
    // n-component (N×C, [k*C + c]; zero where the estimate is balance's), and the factor by which its
    // in-sample residual variance understates the estimate's variance
    // (solver.h, rule 3: S/(S − k − 1)·(S − 2)/(S − k − 2); 1 without α).
    std::vector<double> alpha;
    double fit_inflation = 1;
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
    // The same into `out`, reusing its storage (no allocation per point).
    void result(MisResult& out) const;

    // The balance heuristic's estimate of channel c from the same samples
    // (balance and the optimal strategies accumulate it; the other
    // heuristics' own estimate). Needs complete rounds.
    double balance_estimate(int c) const;
    // Every channel's, into out[C].
    void balance_estimates(double* out) const;

    // Streams (independent randomizations of one point's rounds, issue 7):
    // with set_streams(K), the samples added while stream s is current also
    // go to light per-stream sums — Σ Y per channel and, for the optimal
    // strategies, Σ p_k/q — from which each stream's estimate follows
    // (stream_estimates), with no estimator per stream. set_streams(0), the
    // default, keeps none. Both clear the sums; set_stream needs a round
    // boundary. Not for optimal-progressive, whose per-stream estimate needs
    // its own cross-fit. Throw std::invalid_argument / std::logic_error.
    void set_streams(int count);
    void set_stream(int s);
    int stream_rounds(int s) const;
    // Stream s's balance (or heuristic) estimate into balance[C] and, when
    // corrected is given, that plus Σ_k β_k (1 − ĉ_k) over its own samples
    // into corrected[C] (β without n-component: MisResult::alpha). No
    // checks, no allocation.
    void stream_estimates(int s, const double* beta, double* balance,
                          double* corrected = nullptr) const;
    // optimal-direct: stream s's balance estimate into balance[C] and, into
    // corrected[C], that plus the correction with the α solved from the
    // OTHER streams' samples (cross-fitting by stream): each stream's
    // estimate is then free of its own fit, so the streams' spread includes
    // the fit's error, which a common α hides (issue 10: a noise target's
    // error read 0.5–0.6 of the true one). One solve per stream.
    void stream_cross_fit(int s, double* balance, double* corrected) const;

    // The control-variate estimate (SPEC §2) for a given α (N×C, [k*C + c]);
    // any α ∝ n reproduces the balance estimate bit for bit.
    std::vector<double> control_variate_estimate(const std::vector<double>& alpha) const;

    int num_techniques() const { return N_; }
    int num_channels() const { return C_; }
    const std::vector<int>& counts() const { return counts_; }
    int completed_rounds() const { return rounds_; }
    Strategy strategy() const { return strategy_; }
    void reset();

private:
    void finish_round();
    // add_sample at N = Nt techniques and C = Ct channels (0: N_, C_).
    template <int Nt, int Ct>
    void add_sample_at(int technique, const double* pdfs, const double* f);
    // Full symmetric Â, b̂, m̂ divided by R, in fixed storage (no allocation
    // per point); only the leading N×N, N×C and C entries are set.
    struct Moments {
        std::array<double, kMaxMisTechniques * kMaxMisTechniques> a;
        std::array<double, kMaxMisTechniques * kMaxMisChannels> b;
        std::array<double, kMaxMisChannels> m;
    };
    void normalized_moments(Moments& out) const { moments_without(nullptr, rounds_, out); }
    // The moments of every round so far less those in `part` (a block laid
    // out as moments(): a, b, m; null: none), divided by `rounds`, the rounds
    // left: the other rounds' moments, from which a cross-fit solves.
    void moments_without(const double* part, double rounds, Moments& out) const;
    // Balance estimate plus the control-variate correction for α (N×C).
    double control_variate(const double* alpha, int c) const;
    double heuristic_variance(int c) const;
    void direct_estimate(MisResult& out) const;  // result() of optimal-direct
    // The per-estimate guard (issue 10): a channel's optimal estimate is out of
    // range when it is negative although no sample had f < 0, or (sigmas > 0)
    // when it lies more than `sigmas` balance standard errors from balance.
    bool out_of_range(double estimate, int c, double sigmas, double balance_variance) const;
    // α less its n-component into beta (channel c); false, with beta = 0,
    // when the remainder is at rounding level (α ∝ n: balance).
    bool without_n(const double* alpha, int c, double* beta) const;
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

    // Every sum in one block, so that a reset (per point) is one fill. Per technique t, sums of
    // Y = w_t f/(n_t p_t) and Y² (heuristics; for the optimal strategies Y is
    // the balance contribution f/q) and its sample count; then, for the
    // optimal strategies, Σ p_i p_j/q² (a), Σ p_i f/q² (b), Σ f²/q² (m),
    // Σ p_i/q (c), contiguous in that order (the progressive snapshots' block).
    std::vector<double> sums_;
    double* sum_y() { return sums_.data(); }
    const double* sum_y() const { return sums_.data(); }
    double* sum_y2() { return sums_.data() + N_ * C_; }
    const double* sum_y2() const { return sums_.data() + N_ * C_; }
    double* seen() { return sums_.data() + 2 * N_ * C_; }  // samples per technique
    const double* seen() const { return sums_.data() + 2 * N_ * C_; }
    double* moments() { return seen() + N_; }  // a, b, m, c
    const double* moments() const { return seen() + N_; }
    std::size_t moments_size() const { return is_optimal(strategy_) ? N_ * N_ + N_ * C_ + C_ + N_ : 0; }
    const double* a() const { return moments(); }
    const double* b() const { return moments() + N_ * N_; }
    const double* m() const { return b() + N_ * C_; }
    const double* c() const { return m() + C_; }

    // Progressive: the running moments (a, b, m, c) after rounds 1, 2, 4,
    // 8, ..., one block each: the epoch boundaries of the cross-fit.
    std::vector<double> snapshots_;
    // Per stream: Σ Y per channel, Σ p_k/q per technique (optimal), rounds;
    // optimal-direct also the stream's a, b and m (stream_cross_fit).
    int streams_ = 0, stream_ = 0;
    std::vector<double> stream_sums_;
    bool stream_moments() const { return strategy_ == Strategy::OptimalDirect; }
    int stream_stride() const {
        return C_ + N_ + 1 + (stream_moments() ? N_ * N_ + N_ * C_ + C_ : 0);
    }
    void progressive_estimate(MisResult& out) const;
    // The level test's halves (level_scale in estimator.cpp), levels
    // 1, 2, ... while 2^level ≤ rounds: per level, each channel's balance
    // sum over its first half less its second into D[l*C + c], and the same
    // of Σ p_k/q into c_diff[l*N + k]. Returns the levels.
    static constexpr int kMaxLevels = 32;
    int level_differences(double* D, double* c_diff) const;
    // Optimal strategies: bit c set where any sample had f_c < 0.
    unsigned negative_f_ = 0;
};

}  // namespace omis
