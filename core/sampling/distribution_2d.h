// Piecewise-constant densities on [0,1) and [0,1)² built from tabulated
// weights (pbrt-v4's PiecewiseConstant1D/2D): an environment map's importance
// sampling draws a texel by its row (marginal) and then its column
// (conditional). Only normalised CDFs are stored; a cell's probability is the
// difference of two stored values, so the density returned by pdf() is exactly
// the one sample() draws from, rounding included.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sampling/warp.h"

namespace omis {

// Density on [0,1) constant over n equal cells. Measure: length on [0,1).
class PiecewiseConstant1D {
  public:
    PiecewiseConstant1D() = default;
    // weights: n >= 1 finite, non-negative values; all zero gives the uniform density.
    PiecewiseConstant1D(const double* weights, int n);

    int size() const { return n_; }
    // A point x in [0,1) and its cell; density pdf(x).
    double sample(double u, int* cell) const;
    double pdf(double x) const;
    // Probability of cell i (its density × 1/n).
    double cell_probability(int i) const { return cdf_[i + 1] - cdf_[i]; }
    // The u that sample() maps to x (x inside a cell of positive probability).
    double invert(double x) const;

  private:
    int n_ = 0;
    std::vector<double> cdf_;  // n + 1 values, 0 … 1
};

// Density on [0,1)² constant over a width × height grid of cells, row-major
// (row r covers y in [r/height, (r+1)/height)). Measure: area on [0,1)².
// The rows' conditional CDFs are floats (an 8k × 4k map's weigh 128 MiB
// instead of 256); the marginal over rows is in double.
class PiecewiseConstant2D {
  public:
    PiecewiseConstant2D() = default;
    // weights: width × height finite, non-negative values, row-major.
    PiecewiseConstant2D(const float* weights, int width, int height);

    int width() const { return width_; }
    int height() const { return height_; }
    // A point of [0,1)² drawn from (u1, u2) (u2 picks the row, u1 the column),
    // and its density; pdf 0 only where the weights are all zero (never drawn).
    Point2 sample(double u1, double u2, double* pdf) const;
    double pdf(const Point2& p) const;
    // Probability of cell (column, row).
    double cell_probability(int column, int row) const;
    // The (u1, u2) that sample() maps to p (p in a cell of positive probability).
    Point2 invert(const Point2& p) const;
    std::size_t memory_bytes() const;

  private:
    int width_ = 0, height_ = 0;
    PiecewiseConstant1D rows_;    // marginal over rows
    std::vector<float> columns_;  // per row: width + 1 CDF values, 0 … 1
    const float* row_cdf(int row) const {
        return columns_.data() + std::size_t(row) * (width_ + 1);
    }
};

}  // namespace omis
