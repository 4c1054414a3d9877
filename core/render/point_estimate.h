// A point's estimators and its estimate: how a call's rounds fall into the
// randomisation streams, the estimator pair (main, hidden part) per point and
// stream, the delta lights' sums beside them, the per-stream estimates and
// cross-fitting, and the point's value with its variance. Internal to the
// lighting core (render/*.cpp).
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "mis/estimator.h"
#include "render/direct_lighting.h"

namespace omis {

// The estimators a sample goes to.
struct EstimatorPair {
    MisEstimator* main;
    // A part of the integrand only some techniques estimate (null if none):
    // lights invisible to BSDF rays (the light techniques'), or the world
    // seen through emitters (Integrand::world_through, `bsdf`'s).
    MisEstimator* hidden;
};

// How a call's rounds fall into the streams.
struct RoundPlan {
    int rounds = 0;
    int stream_rounds[kMaxSampleStreams] = {};
    int streams_used = 0;
    bool by_stream = false;  // each stream's estimate is kept
    bool in_whole = false;   // ... as sums inside the whole's estimators
};

// The delta lights' E/π (outside MIS): per stream, or at the centre.
struct DeltaSums {
    bool per_round = false;  // a position per round (else at_centre)
    Vec3 sum[kMaxSampleStreams], sum2, at_centre;
};

class PointEstimate {
public:
    PointEstimate(const LightingContext& context, LightingCounters& counters);

    // How rounds [first_round, first_round + rounds) fall into the streams,
    // and whether each stream's estimate is kept: for the error when asked
    // (want_error), and for the optimal strategies' choice against balance.
    RoundPlan plan_rounds(int first_round, int rounds, bool want_error) const;
    // The estimators of a point's call: one over all rounds (with per-stream
    // sums inside when plan.in_whole), else one more per stream that holds
    // rounds. main: the main estimator's techniques (mask: their bits);
    // hidden: the hidden part's (none: empty). fresh: counts other than the
    // settings' (not cached).
    void set_up(const std::vector<int>& main, std::uint64_t main_mask,
                const std::vector<int>& hidden, std::uint64_t hidden_mask, const RoundPlan& plan,
                const int* counts, bool fresh, EstimatorPair& all, EstimatorPair* per);
    // The stream whose round the whole's estimators take next (plan.in_whole).
    static void set_stream(const EstimatorPair& all, int s);
    // The point's estimate once its rounds are in (sampled: some technique
    // took part). own_variance: as for independent draws; error_variance:
    // from the streams' spread when kept. streams, if given, receives each
    // stream's estimate.
    Vec3 estimate(bool sampled, const RoundPlan& plan, const EstimatorPair& all,
                  const EstimatorPair* per, const DeltaSums& delta, Vec3& own_variance,
                  Vec3& error_variance, StreamEstimates* streams);

private:
    MisEstimator& estimator(std::unordered_map<std::uint64_t, MisEstimator>& cache,
                            std::uint64_t key, const std::vector<int>& active,
                            const int* counts, bool fresh);
    // Sum of the estimates (and their own variance estimates, if asked).
    // The estimators' results stay in results_ (main, hidden) until the next call.
    Vec3 estimate_of(const EstimatorPair& e, Vec3* variance = nullptr);
    // Stream s's estimate from the whole's per-stream sums (streams_in_whole):
    // its balance (heuristics: own) estimate, and (cross_fit, optimal-direct)
    // that corrected with the α of the other streams (MisEstimator::stream_cross_fit).
    void stream_of(const EstimatorPair& whole, int s, bool cross_fit, Vec3& balance,
                   Vec3& corrected) const;
    // The balance heuristic's estimate from the same samples (optimal
    // strategies accumulate it alongside their moments).
    static Vec3 balance_of(const EstimatorPair& e);
    // Whether the whole's estimators keep the per-stream sums (MisEstimator::
    // set_streams) instead of an estimator per stream: every strategy but
    // optimal-progressive, whose stream estimates need their own cross-fit.
    static bool streams_in_whole(Strategy strategy, bool by_stream) {
        return by_stream && strategy != Strategy::OptimalProgressive;
    }
    static void set_streams(const EstimatorPair& all, int count);
    // Optimal strategies: whether the independent streams say the optimal
    // estimate is noisier here than the balance heuristic's.
    static bool balance_is_better(const Vec3* optimal, const Vec3* balance,
                                  const int* stream_rounds);

    const LightingContext& context_;
    LightingCounters& counters_;
    // Without a world, bsdf draws beside every light, where f is 0: an exact
    // fit that leans on its density is not trusted (StrategyOptions::reaches_beyond_f).
    const bool bsdf_reaches_beyond_f_;
    std::unordered_map<std::uint64_t, MisEstimator> main_cache_, hidden_cache_;
    MisResult results_[2];  // estimate_of's (main, hidden), reused from point to point
};

}  // namespace omis
