#include "sampling/distribution_2d.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace omis {

namespace {

// x in cell `cell` of n equal cells by the same test pdf() applies
// (min(int(x·n), n − 1)): (cell + offset)/n may round onto the next cell's edge.
double fit_into_cell(double x, int cell, int n) {
    x = std::min(std::max(x, 0.0), std::nextafter(1.0, 0.0));
    while (std::min(int(x * n), n - 1) > cell) x = std::nextafter(x, 0.0);
    while (std::min(int(x * n), n - 1) < cell) x = std::nextafter(x, 1.0);
    return x;
}

int cell_of(double x, int n) { return std::min(std::max(int(x * n), 0), n - 1); }

void require_weight(double w) {
    if (!(w >= 0) || !std::isfinite(w))
        throw std::invalid_argument(
            "distribution: weights must be finite and non-negative");
}

}  // namespace

PiecewiseConstant1D::PiecewiseConstant1D(const double* weights, int n)
    : n_(n), cdf_(n + 1, 0.0) {
    if (n < 1) throw std::invalid_argument("distribution: needs at least one cell");
    for (int i = 0; i < n; ++i) {
        require_weight(weights[i]);
        cdf_[i + 1] = cdf_[i] + weights[i];
    }
    const double total = cdf_[n];
    for (int i = 1; i < n; ++i) cdf_[i] = total > 0 ? cdf_[i] / total : double(i) / n;
    cdf_[n] = 1.0;
}

double PiecewiseConstant1D::sample(double u, int* cell) const {
    // The first CDF value above u ends the cell u falls in: cells of zero
    // probability are never chosen.
    const auto above = std::upper_bound(cdf_.begin(), cdf_.end(), u);
    const int i = std::min(std::max(int(above - cdf_.begin()) - 1, 0), n_ - 1);
    const double width = cdf_[i + 1] - cdf_[i];
    const double offset = width > 0 ? (u - cdf_[i]) / width : 0.5;
    if (cell) *cell = i;
    return fit_into_cell((i + std::min(std::max(offset, 0.0), 1.0)) / n_, i, n_);
}

double PiecewiseConstant1D::pdf(double x) const {
    if (!(x >= 0 && x < 1)) return 0;
    return cell_probability(cell_of(x, n_)) * n_;
}

double PiecewiseConstant1D::invert(double x) const {
    const int i = cell_of(x, n_);
    return cdf_[i] + (x * n_ - i) * cell_probability(i);
}

PiecewiseConstant2D::PiecewiseConstant2D(const float* weights, int width, int height)
    : width_(width), height_(height) {
    if (width < 1 || height < 1)
        throw std::invalid_argument("distribution: needs at least one cell");
    columns_.resize(std::size_t(height) * (width + 1));
    std::vector<double> row_totals(height), running(width + 1);
    for (int r = 0; r < height; ++r) {
        const float* w = weights + std::size_t(r) * width;
        // Each row's CDF in double, rounded to float once normalised: float
        // values stay non-decreasing, and the last is 1 exactly.
        running[0] = 0;
        for (int i = 0; i < width; ++i) {
            require_weight(w[i]);
            running[i + 1] = running[i] + w[i];
        }
        const double total = running[width];
        row_totals[r] = total;
        float* cdf = columns_.data() + std::size_t(r) * (width + 1);
        cdf[0] = 0;
        for (int i = 1; i < width; ++i)
            cdf[i] = float(total > 0 ? running[i] / total : double(i) / width);
        cdf[width] = 1;
    }
    rows_ = PiecewiseConstant1D(row_totals.data(), height);
}

Point2 PiecewiseConstant2D::sample(double u1, double u2, double* pdf) const {
    int row = 0;
    const double y = rows_.sample(u2, &row);
    const float* cdf = row_cdf(row);
    const float* above = std::upper_bound(
        cdf, cdf + width_ + 1, u1, [](double u, float c) { return u < double(c); });
    const int i = std::min(std::max(int(above - cdf) - 1, 0), width_ - 1);
    const double p = double(cdf[i + 1]) - double(cdf[i]);
    const double offset = p > 0 ? (u1 - double(cdf[i])) / p : 0.5;
    const double x =
        fit_into_cell((i + std::min(std::max(offset, 0.0), 1.0)) / width_, i, width_);
    if (pdf) *pdf = rows_.cell_probability(row) * p * double(width_) * double(height_);
    return {x, y};
}

double PiecewiseConstant2D::cell_probability(int column, int row) const {
    const float* cdf = row_cdf(row);
    return rows_.cell_probability(row) * (double(cdf[column + 1]) - double(cdf[column]));
}

double PiecewiseConstant2D::pdf(const Point2& p) const {
    if (!(p.x >= 0 && p.x < 1 && p.y >= 0 && p.y < 1)) return 0;
    return cell_probability(cell_of(p.x, width_), cell_of(p.y, height_)) *
           double(width_) * double(height_);
}

Point2 PiecewiseConstant2D::invert(const Point2& p) const {
    const int row = cell_of(p.y, height_), column = cell_of(p.x, width_);
    const float* cdf = row_cdf(row);
    const double width = double(cdf[column + 1]) - double(cdf[column]);
    return {double(cdf[column]) + (p.x * width_ - column) * width, rows_.invert(p.y)};
}

std::size_t PiecewiseConstant2D::memory_bytes() const {
    return columns_.capacity() * sizeof(float) +
           std::size_t(height_ + 1) * sizeof(double);
}

}  // namespace omis
