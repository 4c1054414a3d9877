#include "mis/allocation.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace omis {
namespace {

// min over α of m − 2 αᵀb + αᵀAα = m − bᵀα for symmetric PSD A, by Gaussian
// elimination with diagonal pivoting that drops pivots below 1e-12 of the
// largest diagonal (collinear techniques: any α on the solution set gives
// the same minimum).
double minimised_quadratic(int N, std::vector<double> A, std::vector<double> b, double m) {
    double scale = 0;
    for (int i = 0; i < N; ++i) scale = std::max(scale, A[i * N + i]);
    if (!(scale > 0)) return m;
    std::vector<bool> used(N, false);
    double reduction = 0;
    for (int step = 0; step < N; ++step) {
        int p = -1;
        for (int i = 0; i < N; ++i)
            if (!used[i] && (p < 0 || A[i * N + i] > A[p * N + p])) p = i;
        const double pivot = A[p * N + p];
        if (!(pivot > 1e-12 * scale)) break;
        used[p] = true;
        reduction += b[p] * b[p] / pivot;  // Schur complement step
        for (int i = 0; i < N; ++i) {
            if (used[i]) continue;
            const double factor = A[i * N + p] / pivot;
            for (int j = 0; j < N; ++j) A[i * N + j] -= factor * A[p * N + j];
            b[i] -= factor * b[p];
        }
    }
    return std::max(0.0, m - reduction);
}

}  // namespace

AllocationPilot::AllocationPilot(int N, int C, const std::vector<int>& counts)
    : N_(N), C_(C), counts_(counts) {
    if (N < 1) throw std::invalid_argument("num_techniques: need at least 1");
    if (C < 1) throw std::invalid_argument("num_channels: need at least 1");
    if (int(counts.size()) != N)
        throw std::invalid_argument("counts: expected " + std::to_string(N) + " entries");
    if (std::any_of(counts.begin(), counts.end(), [](int n) { return n < 0; }) ||
        std::accumulate(counts.begin(), counts.end(), 0) == 0)
        throw std::invalid_argument("counts: need non-negative counts, at least one positive");
}

void AllocationPilot::add_sample(const double* pdfs, const double* f) {
    for (int k = 0; k < N_; ++k)
        if (!(pdfs[k] >= 0 && std::isfinite(pdfs[k])))
            throw std::invalid_argument("pdfs: density " + std::to_string(k) +
                                        " is negative or not finite");
    for (int c = 0; c < C_; ++c)
        if (!std::isfinite(f[c])) throw std::invalid_argument("f: value is not finite");
    pdfs_.insert(pdfs_.end(), pdfs, pdfs + N_);
    f_.insert(f_.end(), f, f + C_);
}

double AllocationPilot::optimal_variance(const std::vector<double>& shares) const {
    if (int(shares.size()) != N_) throw std::invalid_argument("shares: expected N entries");
    if (rounds_ == 0) throw std::logic_error("allocation: the pilot has no complete round");
    const double total = std::accumulate(shares.begin(), shares.end(), 0.0);
    std::vector<double> A(N_ * N_, 0.0), b(N_ * C_, 0.0), m(C_, 0.0);
    const std::size_t samples = f_.size() / C_;
    for (std::size_t s = 0; s < samples; ++s) {
        const double* p = &pdfs_[s * N_];
        double q = 0, q_w = 0;
        for (int k = 0; k < N_; ++k) {
            q += counts_[k] * p[k];
            q_w += shares[k] / total * p[k];
        }
        // Where q_w = 0 but f ≠ 0 the allocation misses part of the integral.
        const double weight = 1.0 / (q_w * q);
        for (int i = 0; i < N_; ++i) {
            for (int j = 0; j < N_; ++j) A[i * N_ + j] += p[i] * p[j] * weight;
            for (int c = 0; c < C_; ++c) b[i * C_ + c] += p[i] * f_[s * C_ + c] * weight;
        }
        for (int c = 0; c < C_; ++c) m[c] += f_[s * C_ + c] * f_[s * C_ + c] * weight;
    }
    double v = 0;
    for (int c = 0; c < C_; ++c) {
        std::vector<double> bc(N_);
        for (int i = 0; i < N_; ++i) bc[i] = b[i * C_ + c] / rounds_;
        std::vector<double> Ac(A);
        for (double& x : Ac) x /= rounds_;
        v += minimised_quadratic(N_, Ac, bc, m[c] / rounds_);
    }
    return v;
}

std::vector<double> optimal_shares(const AllocationPilot& pilot, const std::vector<double>& cost,
                                   double min_share) {
    const int N = pilot.num_techniques();
    if (int(cost.size()) != N || std::any_of(cost.begin(), cost.end(), [](double c) {
            return !(c > 0) || !std::isfinite(c);
        }))
        throw std::invalid_argument("cost: expected N positive finite entries");
    if (!(min_share >= 0 && min_share * N < 1))
        throw std::invalid_argument("min_share: must lie in [0, 1/N)");
    auto objective = [&](const std::vector<double>& w) {
        double time = 0;
        for (int k = 0; k < N; ++k) time += w[k] * cost[k];
        return pilot.optimal_variance(w) * time;
    };
    // Pairwise transfers of shrinking size: V·time is smooth in w, and with
    // N ≤ 32 techniques this converges in a few hundred evaluations.
    std::vector<double> w(N, 1.0 / N);
    double best = objective(w);
    for (double step = 0.25; step > 1e-3; step /= 2) {
        bool improved = true;
        while (improved) {
            improved = false;
            for (int from = 0; from < N; ++from)
                for (int to = 0; to < N; ++to) {
                    if (from == to) continue;
                    const double move = std::min(step, w[from] - min_share);
                    if (move <= 0) continue;
                    std::vector<double> trial = w;
                    trial[from] -= move;
                    trial[to] += move;
                    const double value = objective(trial);
                    if (value < best) {
                        best = value;
                        w = trial;
                        improved = true;
                    }
                }
        }
    }
    return w;
}

std::vector<int> counts_from_shares(const std::vector<double>& shares, int total) {
    const int N = int(shares.size());
    if (N < 1 || total < N) throw std::invalid_argument("total: need at least one sample per technique");
    const double sum = std::accumulate(shares.begin(), shares.end(), 0.0);
    std::vector<int> counts(N, 1);
    std::vector<double> remainder(N);
    int left = total - N;
    const int spare = left;
    for (int k = 0; k < N; ++k) {
        const double ideal = shares[k] / sum * spare;
        counts[k] += int(std::floor(ideal));
        left -= int(std::floor(ideal));
        remainder[k] = ideal - std::floor(ideal);
    }
    std::vector<int> order(N);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return remainder[a] > remainder[b]; });
    for (int i = 0; i < left; ++i) ++counts[order[i % N]];
    return counts;
}

}  // namespace omis
