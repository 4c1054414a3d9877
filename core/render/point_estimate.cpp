// A point's estimators and its estimate: the estimator pair (main, hidden
// part), the per-stream estimates and cross-fitting, the variance.
#include "render/point_estimate.h"

#include <algorithm>

namespace omis {

PointEstimate::PointEstimate(const LightingContext& context, LightingCounters& counters)
    : context_(context),
      counters_(counters),
      bsdf_reaches_beyond_f_(std::none_of(
          context.scene.lights().begin(), context.scene.lights().end(),
          [](const Light& l) { return l.type == LightType::World; })) {}

// How a call's rounds fall into the streams, and whether each stream's
// estimate is kept: for the error when asked, and for the optimal strategies'
// choice against balance (balance_is_better).
RoundPlan PointEstimate::plan_rounds(int first_round, int rounds, bool want_error) const {
    RoundPlan plan;
    plan.rounds = rounds;
    const int streams = context_.settings.streams;
    for (int r = first_round; r < first_round + rounds; ++r) ++plan.stream_rounds[r % streams];
    plan.streams_used = int(std::count_if(plan.stream_rounds, plan.stream_rounds + streams,
                                          [](int m) { return m > 0; }));
    plan.by_stream = plan.streams_used >= 2 && (want_error || is_optimal(context_.settings.strategy));
    plan.in_whole = streams_in_whole(context_.settings.strategy, plan.by_stream);
    return plan;
}

MisEstimator& PointEstimate::estimator(std::unordered_map<std::uint64_t, MisEstimator>& cache,
                                             std::uint64_t key, const std::vector<int>& active,
                                             const int* counts, bool fresh) {
    auto it = cache.find(key);
    // Counts other than the settings' (a final partial pass, an allocated
    // tile's): kept while the next point asks for the same.
    auto same_counts = [&](const MisEstimator& e) {
        for (std::size_t a = 0; a < active.size(); ++a)
            if (e.counts()[a] != counts[active[a]]) return false;
        return true;
    };
    if (it != cache.end() && fresh && !same_counts(it->second)) {
        cache.erase(it);
        it = cache.end();
    }
    if (it == cache.end()) {
        std::vector<int> n;
        for (int k : active) n.push_back(counts[k]);
        StrategyOptions options = context_.settings.options;
        options.sequence_rounds = true;  // each technique draws one scrambled sequence
        for (std::size_t a = 0; a < active.size() && bsdf_reaches_beyond_f_; ++a)
            if (context_.settings.techniques[active[a]].bsdf) options.reaches_beyond_f |= 1u << a;
        // One technique: every weighting is 1 and the optimal α is the mean
        // itself, so each strategy's estimate is the plain mean of f/p, which
        // the balance heuristic forms without the optimal moments and solve
        // (~5 % of a one-round pass on the race's one-technique scenes).
        const Strategy strategy = active.size() == 1 ? Strategy::Balance : context_.settings.strategy;
        it = cache.emplace(key, MisEstimator(strategy, int(active.size()), 3, n, options))
                 .first;
    }
    it->second.reset();
    return it->second;
}

Vec3 PointEstimate::balance_of(const EstimatorPair& e) {
    Vec3 total;
    for (const MisEstimator* m : {e.main, e.hidden}) {
        if (!m) continue;
        double b[3];
        m->balance_estimates(b);
        total += Vec3(b[0], b[1], b[2]);
    }
    return total;
}

void PointEstimate::set_streams(const EstimatorPair& all, int count) {
    all.main->set_streams(count);
    if (all.hidden) all.hidden->set_streams(count);
}

void PointEstimate::set_stream(const EstimatorPair& all, int s) {
    all.main->set_stream(s);
    if (all.hidden) all.hidden->set_stream(s);
}

// With a low-discrepancy sequence the balance heuristic can converge faster
// than the optimal weights' control variate, whose α is estimated from the
// same few samples (issue 10: optimal MIS must never lose). The K streams are
// independent randomizations, so the spread of their estimates measures each
// estimator's actual error; the point keeps whichever spreads less (luminance,
// weighted by the streams' rounds). A selection from 4 streams is noisy, but
// it picks between two unbiased-or-consistent estimates of the same value.
bool PointEstimate::balance_is_better(const Vec3* optimal, const Vec3* balance,
                                            const int* stream_rounds) {
    double rounds = 0, mean_o = 0, mean_b = 0;
    double opt[kMaxSampleStreams], bal[kMaxSampleStreams];
    for (int s = 0; s < kMaxSampleStreams; ++s) {
        if (!stream_rounds[s]) continue;
        opt[s] = luminance(optimal[s]);
        bal[s] = luminance(balance[s]);
        rounds += stream_rounds[s];
        mean_o += opt[s] * stream_rounds[s];
        mean_b += bal[s] * stream_rounds[s];
    }
    mean_o /= rounds;
    mean_b /= rounds;
    double spread_o = 0, spread_b = 0;
    for (int s = 0; s < kMaxSampleStreams; ++s) {
        if (!stream_rounds[s]) continue;
        spread_o += stream_rounds[s] * (opt[s] - mean_o) * (opt[s] - mean_o);
        spread_b += stream_rounds[s] * (bal[s] - mean_b) * (bal[s] - mean_b);
    }
    return spread_b < spread_o;
}

Vec3 PointEstimate::estimate_of(const EstimatorPair& e, Vec3* variance) {
    Vec3 total;
    const MisEstimator* estimators[2] = {e.main, e.hidden};
    for (int i = 0; i < 2; ++i) {
        if (!estimators[i]) continue;
        MisResult& r = results_[i];
        estimators[i]->result(r);
        total += Vec3(r.estimate[0], r.estimate[1], r.estimate[2]);
        if (variance) *variance += Vec3(r.variance[0], r.variance[1], r.variance[2]);
    }
    return total;
}

// optimal-direct's stream s is corrected with the α solved from the other
// streams (cross-fitting by stream): the streams' spread then holds the
// fit's error too, which one α common to all of them hides (issue 10).
void PointEstimate::stream_of(const EstimatorPair& whole, int s, bool cross_fit,
                                    Vec3& balance, Vec3& corrected) const {
    balance = corrected = Vec3();
    const MisEstimator* estimators[2] = {whole.main, whole.hidden};
    for (int i = 0; i < 2; ++i) {
        if (!estimators[i]) continue;
        double b[3], e[3];
        if (cross_fit)
            estimators[i]->stream_cross_fit(s, b, e);
        else
            estimators[i]->stream_estimates(s, nullptr, b);
        balance += Vec3(b[0], b[1], b[2]);
        corrected += cross_fit ? Vec3(e[0], e[1], e[2]) : Vec3(b[0], b[1], b[2]);
    }
}


// Estimators: one over all rounds (with per-stream sums inside when
// plan.in_whole), else one more per stream that holds rounds.
void PointEstimate::set_up(const std::vector<int>& main, std::uint64_t main_mask,
                           const std::vector<int>& hidden_techniques, std::uint64_t hidden_mask,
                           const RoundPlan& plan, const int* counts, bool fresh,
                           EstimatorPair& all, EstimatorPair* per) {
    const std::uint64_t fresh_key = fresh ? std::uint64_t(1) << 50 : 0;  // uncached counts
    const bool hidden = !hidden_techniques.empty();
    for (int s = -1; s < context_.settings.streams; ++s) {
        if (s >= 0 && (!plan.by_stream || plan.in_whole || plan.stream_rounds[s] == 0)) continue;
        const std::uint64_t key = fresh_key | (std::uint64_t(s + 1) << 40);
        EstimatorPair& e = s < 0 ? all : per[s];
        if (s < 0) counters_.systems += hidden ? 2 : 1;  // streams only measure the error
        e.main = &estimator(main_cache_, key | main_mask, main, counts, fresh);
        if (hidden)
            e.hidden = &estimator(hidden_cache_, key | hidden_mask, hidden_techniques, counts,
                                  fresh);
    }
    set_streams(all, plan.in_whole ? context_.settings.streams : 0);
}

// The point's estimate once its rounds are in: the whole's estimate, then
// each stream's — the optimal strategies compare it with balance's
// (balance_is_better), and the chosen one's spread is the error;
// optimal-direct's streams are cross-fitted (stream_of) and their mean is its
// estimate, so that spread is its error. own_variance: as for
// independent draws; error_variance: from the streams' spread when kept.
Vec3 PointEstimate::estimate(bool sampled, const RoundPlan& plan, const EstimatorPair& all,
                              const EstimatorPair* per, const DeltaSums& delta,
                              Vec3& own_variance, Vec3& error_variance,
                              StreamEstimates* streams) {
    constexpr int K = kMaxSampleStreams;  // streams past settings.streams hold no rounds
    const int rounds = plan.rounds;
    const bool optimal = is_optimal(context_.settings.strategy);
    const bool direct = context_.settings.strategy == Strategy::OptimalDirect;
    own_variance = Vec3();
    Vec3 whole, total = delta.at_centre;
    if (sampled) whole = estimate_of(all, &own_variance);
    Vec3 stream_estimate[K], stream_balance[K];
    if (plan.by_stream && sampled)
        for (int s = 0; s < K; ++s) {
            if (!plan.stream_rounds[s]) continue;
            if (!plan.in_whole) {  // optimal-progressive: its own cross-fit per stream
                stream_balance[s] = balance_of(per[s]);
                stream_estimate[s] = estimate_of(per[s]);
                continue;
            }
            // The heuristics' own estimate; optimal-direct's cross-fitted.
            stream_of(all, s, direct, stream_balance[s], stream_estimate[s]);
        }
    const bool cross_fitted = sampled && direct && plan.in_whole;
    if (cross_fitted) {  // the streams' mean, unless negative where balance is not
        Vec3 mean;
        for (int s = 0; s < K; ++s)
            mean += stream_estimate[s] * (double(plan.stream_rounds[s]) / rounds);
        const Vec3 balance = balance_of(all);
        const bool negative = (mean.x < 0 && balance.x >= 0) || (mean.y < 0 && balance.y >= 0) ||
                              (mean.z < 0 && balance.z >= 0);
        whole = negative ? balance : mean;
        if (negative)
            for (int s = 0; s < K; ++s) stream_estimate[s] = stream_balance[s];
    }
    const bool use_balance =
        sampled && plan.by_stream && optimal &&
        balance_is_better(stream_estimate, stream_balance, plan.stream_rounds);
    if (sampled) total += use_balance ? balance_of(all) : whole;
    Vec3 delta_total;
    for (const Vec3& d : delta.sum) delta_total += d;
    total += delta_total / double(rounds);
    if (rounds > 1) {  // the delta lights' mean over positions, as independent draws
        const Vec3 m = delta_total / double(rounds);
        const Vec3 spread = delta.sum2 / double(rounds) - Vec3(m.x * m.x, m.y * m.y, m.z * m.z);
        own_variance += Vec3(std::max(0.0, spread.x), std::max(0.0, spread.y),
                             std::max(0.0, spread.z)) / double(rounds - 1);
    }
    error_variance = own_variance;
    if (!plan.by_stream) {
        if (streams && plan.streams_used == 1)  // the one stream's estimate is the point's
            for (int s = 0; s < K; ++s)
                if (plan.stream_rounds[s]) {
                    streams->rounds[s] = plan.stream_rounds[s];
                    streams->luminance[s] = luminance(total);
                }
        return total;
    }
    // Var(mean) = Σ m_s (e_s − ē)² / ((S − 1) M): the streams' estimates e_s
    // are independent with variance σ²/m_s.
    Vec3 e[K], mean;
    for (int s = 0; s < K; ++s) {
        if (!plan.stream_rounds[s]) continue;
        e[s] = delta.sum[s] / double(plan.stream_rounds[s]);
        if (sampled) e[s] += use_balance ? stream_balance[s] : stream_estimate[s];
        mean += e[s] * (double(plan.stream_rounds[s]) / rounds);
    }
    if (streams)
        for (int s = 0; s < K; ++s) {
            if (!plan.stream_rounds[s]) continue;
            streams->rounds[s] = plan.stream_rounds[s];
            streams->luminance[s] = luminance(e[s]);
        }
    error_variance = Vec3();
    for (int s = 0; s < K; ++s) {
        if (!plan.stream_rounds[s]) continue;
        const Vec3 d = e[s] - mean;
        error_variance += Vec3(d.x * d.x, d.y * d.y, d.z * d.z) * double(plan.stream_rounds[s]);
    }
    error_variance = error_variance / (double(plan.streams_used - 1) * rounds);
    return total;
}

}  // namespace omis
