#include "mis/allocation.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace omis {
namespace {

// Minimises m − 2 αᵀb + αᵀAα (= m − bᵀα at the minimum) for symmetric PSD A
// by Gaussian elimination with diagonal pivoting that drops pivots below
// 1e-12 of the largest diagonal (collinear techniques: any α on the solution
// set gives the same minimum; a dropped technique gets α = 0). Returns the
// minimum; alpha[N] receives the minimiser.
double minimise_quadratic(int N, double* A, double* b, double m, double* alpha) {
    std::fill(alpha, alpha + N, 0.0);
    double scale = 0;
    for (int i = 0; i < N; ++i) scale = std::max(scale, A[i * N + i]);
    if (!(scale > 0)) return m;
    bool used[64] = {};
    int order[64], pivots = 0;
    double reduction = 0;
    for (int step = 0; step < N; ++step) {
        int p = -1;
        for (int i = 0; i < N; ++i)
            if (!used[i] && (p < 0 || A[i * N + i] > A[p * N + p])) p = i;
        const double pivot = A[p * N + p];
        if (!(pivot > 1e-12 * scale)) break;
        used[p] = true;
        order[pivots++] = p;
        reduction += b[p] * b[p] / pivot;  // Schur complement step
        for (int i = 0; i < N; ++i) {
            if (used[i]) continue;
            const double factor = A[i * N + p] / pivot;
            for (int j = 0; j < N; ++j) A[i * N + j] -= factor * A[p * N + j];
            b[i] -= factor * b[p];
        }
    }
    // Row order[t] was reduced by the pivots before it: back-substitute.
    for (int t = pivots - 1; t >= 0; --t) {
        const int p = order[t];
        double r = b[p];
        for (int u = t + 1; u < pivots; ++u) r -= A[p * N + order[u]] * alpha[order[u]];
        alpha[p] = r / A[p * N + p];
    }
    return std::max(0.0, m - reduction);
}

}  // namespace

AllocationPilot::AllocationPilot(int N, int C, const std::vector<int>& counts)
    : N_(N), C_(C), counts_(counts), work_(std::max(N, 0), 0.0), draws_(std::max(N, 0), 0.0) {
    if (N < 1 || N > 64) throw std::invalid_argument("num_techniques: need 1 to 64");
    if (C < 1) throw std::invalid_argument("num_channels: need at least 1");
    if (int(counts.size()) != N)
        throw std::invalid_argument("counts: expected " + std::to_string(N) + " entries");
    if (std::any_of(counts.begin(), counts.end(), [](int n) { return n < 0; }) ||
        std::accumulate(counts.begin(), counts.end(), 0) == 0)
        throw std::invalid_argument("counts: need non-negative counts, at least one positive");
}

void AllocationPilot::add_sample(const double* pdfs, const double* f) {
    double q = 0;
    for (int k = 0; k < N_; ++k) {
        if (!(pdfs[k] >= 0 && std::isfinite(pdfs[k])))
            throw std::invalid_argument("pdfs: density " + std::to_string(k) +
                                        " is negative or not finite");
        q += counts_[k] * pdfs[k];
    }
    for (int c = 0; c < C_; ++c)
        if (!std::isfinite(f[c])) throw std::invalid_argument("f: value is not finite");
    if (!(q > 0)) return;  // no technique could have drawn it: a null draw
    pdfs_.insert(pdfs_.end(), pdfs, pdfs + N_);
    f_.insert(f_.end(), f, f + C_);
    q_.push_back(q);
}

void AllocationPilot::end_point(double scale, int rounds) {
    if (!std::isfinite(scale) || scale < 0)
        throw std::invalid_argument("scale: must be finite and non-negative");
    if (rounds < 0) throw std::invalid_argument("rounds: must not be negative");
    for (std::size_t i = point_begin_ * C_; i < f_.size(); ++i) f_[i] *= scale;
    point_begin_ = q_.size();
    rounds_ += rounds;
}

void AllocationPilot::add_work(int technique, double units) {
    if (technique < 0 || technique >= N_) throw std::invalid_argument("technique: out of range");
    work_[technique] += units;
    draws_[technique] += 1;
}

std::vector<double> AllocationPilot::cost() const {
    std::vector<double> c(N_, 1.0);
    for (int k = 0; k < N_; ++k)
        if (draws_[k] > 0 && work_[k] > 0) c[k] = work_[k] / draws_[k];
    return c;
}

double AllocationPilot::optimal_variance(const std::vector<double>& shares,
                                         std::vector<double>* gradient) const {
    if (int(shares.size()) != N_) throw std::invalid_argument("shares: expected N entries");
    if (rounds_ == 0) throw std::logic_error("allocation: the pilot has no complete round");
    std::vector<double> A(N_ * N_, 0.0), b(N_ * C_, 0.0), m(C_, 0.0);
    const std::size_t S = q_.size();
    const double total = std::accumulate(shares.begin(), shares.end(), 0.0);
    if (!(total > 0)) throw std::invalid_argument("shares: need a positive sum");
    std::vector<double> q_w(S);
    for (std::size_t s = 0; s < S; ++s) {
        const double* p = &pdfs_[s * N_];
        double qw = 0;
        for (int k = 0; k < N_; ++k) qw += shares[k] / total * p[k];
        q_w[s] = qw;
        // Where q_w = 0 but f ≠ 0 the allocation misses part of the integral.
        if (!(qw > 0)) return HUGE_VAL;
        const double weight = 1.0 / (qw * q_[s]);
        for (int i = 0; i < N_; ++i) {
            const double pi = p[i] * weight;
            for (int j = i; j < N_; ++j) A[i * N_ + j] += pi * p[j];
            for (int c = 0; c < C_; ++c) b[i * C_ + c] += pi * f_[s * C_ + c];
        }
        for (int c = 0; c < C_; ++c) m[c] += f_[s * C_ + c] * f_[s * C_ + c] * weight;
    }
    for (int i = 0; i < N_; ++i)
        for (int j = 0; j < i; ++j) A[i * N_ + j] = A[j * N_ + i];
    std::vector<double> alpha(N_ * C_), Ac(N_ * N_), bc(N_), ac(N_);
    double v = 0;
    for (int c = 0; c < C_; ++c) {
        for (int i = 0; i < N_ * N_; ++i) Ac[i] = A[i] / rounds_;
        for (int i = 0; i < N_; ++i) bc[i] = b[i * C_ + c] / rounds_;
        v += minimise_quadratic(N_, Ac.data(), bc.data(), m[c] / rounds_, ac.data());
        for (int i = 0; i < N_; ++i) alpha[i * C_ + c] = ac[i];
    }
    if (!gradient) return v;
    // Envelope theorem: at the optimal α, ∂V/∂w_k = −∫ (f − g)² p_k / q_w².
    gradient->assign(N_, 0.0);
    for (std::size_t s = 0; s < S; ++s) {
        const double* p = &pdfs_[s * N_];
        double r2 = 0;
        for (int c = 0; c < C_; ++c) {
            double r = f_[s * C_ + c];
            for (int k = 0; k < N_; ++k) r -= alpha[k * C_ + c] * p[k];
            r2 += r * r;
        }
        const double weight = r2 / (q_w[s] * q_w[s] * q_[s] * rounds_);
        for (int k = 0; k < N_; ++k) (*gradient)[k] += p[k] * weight;
    }
    return v;
}

namespace {

// Shares at least min_share where allowed, 0 elsewhere, summing to 1.
void project(std::vector<double>& w, const std::vector<bool>& allowed, double min_share) {
    double sum = 0;
    for (std::size_t k = 0; k < w.size(); ++k) sum += allowed[k] ? w[k] : 0.0;
    for (std::size_t k = 0; k < w.size(); ++k) w[k] = allowed[k] ? w[k] / sum : 0.0;
    // Raise those below the floor; take the excess from the others in proportion.
    double raised = 0, rest = 0;
    for (std::size_t k = 0; k < w.size(); ++k) {
        if (!allowed[k]) continue;
        if (w[k] < min_share) raised += min_share - w[k];
        else rest += w[k] - min_share;
    }
    if (raised <= 0) return;
    for (std::size_t k = 0; k < w.size(); ++k) {
        if (!allowed[k]) continue;
        w[k] = w[k] < min_share ? min_share
                                : min_share + (w[k] - min_share) * (1 - raised / rest);
    }
}

}  // namespace

std::vector<double> optimal_shares(const AllocationPilot& pilot, const std::vector<double>& cost,
                                   double min_share) {
    const int N = pilot.num_techniques();
    if (int(cost.size()) != N || std::any_of(cost.begin(), cost.end(), [](double c) {
            return !(c > 0) || !std::isfinite(c);
        }))
        throw std::invalid_argument("cost: expected N positive finite entries");
    std::vector<bool> allowed(N);
    int n_allowed = 0;
    for (int k = 0; k < N; ++k) n_allowed += allowed[k] = pilot.counts()[k] > 0;
    if (!(min_share >= 0 && min_share * n_allowed < 1))
        throw std::invalid_argument("min_share: must lie in [0, 1/techniques)");
    auto time = [&](const std::vector<double>& w) {
        double t = 0;
        for (int k = 0; k < N; ++k) t += w[k] * cost[k];
        return t;
    };
    // Start from the pilot's own shares (the fallback: never worse by the
    // pilot's estimate). At the optimum of V·T (V homogeneous of degree −1 in
    // w, T of degree 1), −∂V/∂w_k / cost_k = V/T for every free technique;
    // the damped multiplicative update w_k ← w_k √(g_k T / (cost_k V)) has
    // that fixed point and keeps shares positive.
    std::vector<double> w(pilot.counts().begin(), pilot.counts().end()), g;
    project(w, allowed, 0.0);
    std::vector<double> best = w;
    double best_value = pilot.optimal_variance(w, &g) * time(w);
    for (int iteration = 0; iteration < 12; ++iteration) {
        const double v = pilot.optimal_variance(w, &g), t = time(w);
        if (!(v > 0) || !std::isfinite(v)) break;  // nothing to reduce
        if (iteration > 0 && v * t < best_value) {
            best_value = v * t;
            best = w;
        }
        std::vector<double> next = w;
        double change = 0;
        for (int k = 0; k < N; ++k) {
            if (!allowed[k]) continue;
            next[k] = w[k] * std::sqrt(std::max(g[k], 0.0) * t / (cost[k] * v));
        }
        project(next, allowed, min_share);
        for (int k = 0; k < N; ++k) change = std::max(change, std::abs(next[k] - w[k]));
        w = next;
        if (change < 1e-3) break;  // finer than any round's counts resolve
    }
    const double last = pilot.optimal_variance(w) * time(w);
    if (last < best_value) best = w;
    // The pilot's shares may sit below the floor: only a chosen allocation
    // must respect it.
    return best;
}

std::vector<int> counts_from_shares(const std::vector<double>& shares, int total) {
    const int N = int(shares.size());
    const int positive = int(std::count_if(shares.begin(), shares.end(), [](double s) { return s > 0; }));
    if (N < 1 || positive < 1 || total < positive)
        throw std::invalid_argument("total: need at least one sample per technique with a share");
    const double sum = std::accumulate(shares.begin(), shares.end(), 0.0);
    std::vector<int> counts(N, 0);
    std::vector<double> remainder(N, -1.0);
    const int spare = total - positive;
    int left = spare;
    for (int k = 0; k < N; ++k) {
        if (!(shares[k] > 0)) continue;
        const double ideal = shares[k] / sum * spare;
        counts[k] = 1 + int(std::floor(ideal));
        left -= int(std::floor(ideal));
        remainder[k] = ideal - std::floor(ideal);
    }
    std::vector<int> order(N);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return remainder[a] > remainder[b]; });
    for (int i = 0; i < left; ++i) ++counts[order[i % positive]];
    return counts;
}

}  // namespace omis
