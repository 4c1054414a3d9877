// Solid-angle sampling of a spherical polygon bent toward the receiver's cosine
// (after pbrt-v4, which samples large spherical triangles and rectangles so,
// after Hart et al. 2020): the uniform parametrisation's unit square is first
// warped by a bilinear density through cos θ at the directions the square's
// corners map to (floored at kMinCosine, so no part of the light loses its
// density). For a light off to the side of x the draws then follow cos θ
// closely, while the monotone warp keeps a low-discrepancy sequence's strata,
// and a small light is drawn nearly uniformly. Density:
// pdf_piecewise_bilinear(invert(w))/Ω.
//
// kPatches = 2 (a 3 × 3 grid of nodes) also follows the peak of cos θ when x
// lies under the light, but its inner nodes cost a spherical rectangle's
// Newton solve each at every sample position: measured on the Cycles race it
// made samples ~3× dearer, far more than it saved. Corners cost no solve.
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>

#include "sampling/spherical.h"
#include "sampling/warp.h"

namespace omis {

template <class SphericalShape>
class CosineWarped {
public:
    static constexpr double kMinCosine = 0.01;
    static constexpr int kPatches = 1;  // per side; nodes (kPatches + 1)²
    static constexpr int kNodes = (kPatches + 1) * (kPatches + 1);

    // n: the receiver's normal (unit).
    CosineWarped(const SphericalShape& shape, const Vec3& n) : shape_(shape) {
        node_weights(shape_, n, w_);
    }
    // The node weights: cos θ at the directions node (i, j) maps to, floored.
    // With one patch the nodes are the square's corners, which the shapes map
    // to their own corners in closed form (corner_direction) — the same
    // directions sample() reaches, without its Newton solves (four per
    // sample position cost ~20 % of a footprint sample).
    static void node_weights(const SphericalShape& shape, const Vec3& n, double* w) {
        static_assert(kPatches == 1, "inner nodes need shape.sample()");
        for (int j = 0; j <= kPatches; ++j)
            for (int i = 0; i <= kPatches; ++i) {
                const double c = dot(n, shape.corner_direction(i, j));
                w[j * (kPatches + 1) + i] = std::isfinite(c) ? std::max(kMinCosine, c) : 1.0;
            }
    }
    const SphericalShape& shape() const { return shape_; }
    double solid_angle() const { return shape_.solid_angle(); }

    // The direction, the distance to the light, and the density (sr⁻¹).
    DirSample sample(double u1, double u2, double& pdf) const {
        const Point2 p = sample_piecewise_bilinear(u1, u2, w_, kPatches);
        pdf = pdf_piecewise_bilinear(p, w_, kPatches) / shape_.solid_angle();
        return shape_.sample(p.x, p.y);
    }
    // Solid angle: 0 where w misses the shape.
    double pdf(const Vec3& w) const {
        const std::optional<Point2> u = invert_if_hit(shape_, w);
        if (!u) return 0.0;
        return pdf_piecewise_bilinear(*u, w_, kPatches) / shape_.solid_angle();
    }

private:
    // shape.invert(w) where w hits the shape, else empty.
    template <class Shape>
    static std::optional<Point2> invert_if_hit(const Shape& shape, const Vec3& w) {
        if (!(shape.pdf(w) > 0)) return std::nullopt;
        return shape.invert(w);
    }
    static std::optional<Point2> invert_if_hit(const SphericalTriangle& shape, const Vec3& w) {
        return shape.invert_if_hit(w);
    }
    SphericalShape shape_;
    double w_[kNodes];
};

}  // namespace omis
