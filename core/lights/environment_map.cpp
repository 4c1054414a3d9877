#include "lights/environment_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "lights/light.h"

namespace omis {

namespace {

constexpr int kMaxSide = 1 << 16;

void validate(const std::vector<float>& rgb, int width, int height,
              const Vec3& rotation) {
    if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
        throw std::invalid_argument(
            "world image: width and height must be in 1.." + std::to_string(kMaxSide) +
            ", got " + std::to_string(width) + " x " + std::to_string(height));
    if (rgb.size() != std::size_t(width) * std::size_t(height) * 3)
        throw std::invalid_argument("world image: expected width x height x 3 = " +
                                    std::to_string(std::size_t(width) * height * 3) +
                                    " floats, got " + std::to_string(rgb.size()));
    if (!isfinite(rotation))
        throw std::invalid_argument("world image: rotation must be finite");
    for (std::size_t i = 0; i < rgb.size(); ++i) {
        const float v = rgb[i];
        if (std::isfinite(v) && v >= 0) continue;
        const std::size_t texel = i / 3;
        const char* what =
            std::isnan(v) ? "NaN" : (std::isinf(v) ? "infinite" : "negative");
        throw std::invalid_argument(
            "world image: texel (row " + std::to_string(texel / width) + ", column " +
            std::to_string(texel % width) + ", channel " + std::to_string(i % 3) +
            ") is " + what + "; radiance must be finite and non-negative");
    }
}

// Rows of R = Rz(z)·Ry(y)·Rx(x), Cycles' euler_to_transform.
std::array<Vec3, 3> euler_xyz_matrix(const Vec3& e) {
    const double cx = std::cos(e.x), sx = std::sin(e.x), cy = std::cos(e.y),
                 sy = std::sin(e.y), cz = std::cos(e.z), sz = std::sin(e.z);
    return {Vec3{cy * cz, sy * sx * cz - cx * sz, sy * cx * cz + sx * sz},
            Vec3{cy * sz, sy * sx * sz + cx * cz, sy * cx * sz - sx * cz},
            Vec3{-sy, cy * sx, cy * cx}};
}

}  // namespace

Point2 EnvironmentMap::direction_to_equirectangular(const Vec3& d) {
    double u = 0.5 - std::atan2(d.y, d.x) / (2 * kPi);
    if (u >= 1) u -= 1;  // atan2 = −π: the seam, u = 0
    // θ from atan2, not acos: exact near the poles.
    const double theta = std::atan2(std::sqrt(d.x * d.x + d.y * d.y), d.z);
    return {std::max(0.0, u), 1 - theta / kPi};
}

Vec3 EnvironmentMap::equirectangular_to_direction(const Point2& uv) {
    const double phi = kPi * (1 - 2 * uv.x), theta = kPi * (1 - uv.y);
    const double s = std::sin(theta);
    return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

EnvironmentMap::EnvironmentMap(std::vector<float> rgb, int width, int height,
                               const Vec3& rotation, bool compensate)
    : width_(width), height_(height), rotation_(rotation), compensate_(compensate) {
    validate(rgb, width, height, rotation);
    rgb_ = std::move(rgb);
    to_map_ = euler_xyz_matrix(rotation);
    // Per row (θ from rθ0 to θ1): the solid angle of a texel, (2π/W)(cos θ0 − cos θ1),
    // and the mean sin θ over the row, (cos θ0 − cos θ1)/(θ1 − θ0).
    std::vector<double> row_solid_angle(height), row_mean_sin(height);
    for (int r = 0; r < height; ++r) {
        const double t0 = kPi * r / height, t1 = kPi * (r + 1) / height;
        const double band = std::cos(t0) - std::cos(t1);
        row_solid_angle[r] = 2 * kPi / width * band;
        row_mean_sin[r] = band / (t1 - t0);
    }
    std::vector<float> weights(std::size_t(width) * height);
    double integral_luminance = 0;
    Vec3 integral;
    for (int r = 0; r < height; ++r) {
        Vec3 row_sum;
        for (int c = 0; c < width; ++c) {
            const Vec3 l = texel(c, r);
            row_sum += l;
            weights[std::size_t(r) * width + c] = float(luminance(l));
        }
        integral += row_sum * row_solid_angle[r];
        integral_luminance += luminance(row_sum) * row_solid_angle[r];
    }
    integral_ = integral;
    // Compensation keeps what lies above the mean (in solid angle); a map with
    // nothing above it (a constant one) keeps the plain weights.
    const double mean = integral_luminance / (4 * kPi);
    if (compensate) {
        bool any = false;
        // Above it by more than the rounding of a float luminance.
        for (float w : weights) any = any || w - mean > 1e-6 * mean;
        compensation_applied_ = any;
    }
    for (int r = 0; r < height; ++r)
        for (int c = 0; c < width; ++c) {
            float& w = weights[std::size_t(r) * width + c];
            const double lum =
                compensation_applied_ ? std::max(0.0, w - mean) : double(w);
            w = float(std::max(0.0, lum) * row_mean_sin[r]);
        }
    distribution_ = PiecewiseConstant2D(weights.data(), width, height);
}

Vec3 EnvironmentMap::texel(int column, int row) const {
    const float* p = rgb_.data() + (std::size_t(row) * width_ + column) * 3;
    return {p[0], p[1], p[2]};
}

Point2 EnvironmentMap::to_map_point(const Vec3& w) const {
    const Vec3 d{dot(to_map_[0], w), dot(to_map_[1], w), dot(to_map_[2], w)};
    const Point2 uv = direction_to_equirectangular(d);
    return {uv.x, std::min(1 - uv.y, std::nextafter(1.0, 0.0))};
}

Vec3 EnvironmentMap::from_map_point(const Point2& p, double* sin_theta) const {
    const Vec3 d = equirectangular_to_direction({p.x, 1 - p.y});
    if (sin_theta) *sin_theta = std::sin(kPi * p.y);
    // w = Rᵀ·d
    return to_map_[0] * d.x + to_map_[1] * d.y + to_map_[2] * d.z;
}

Vec3 EnvironmentMap::radiance(const Vec3& w) const {
    const Point2 p = to_map_point(w);
    const int c = std::min(int(p.x * width_), width_ - 1),
              r = std::min(int(p.y * height_), height_ - 1);
    return texel(c, r);
}

std::optional<LightSample> EnvironmentMap::sample(double u1, double u2) const {
    double pdf_area = 0;
    const Point2 p = distribution_.sample(u1, u2, &pdf_area);
    double sin_theta = 0;
    const Vec3 w = from_map_point(p, &sin_theta);
    if (!(pdf_area > 0) || !(sin_theta > 0)) return std::nullopt;
    return LightSample{normalize(w), std::numeric_limits<double>::infinity(),
                       pdf_area / (2 * kPi * kPi * sin_theta)};
}

double EnvironmentMap::pdf(const Vec3& w) const {
    const Point2 p = to_map_point(w);
    const double sin_theta = std::sin(kPi * p.y);
    if (!(sin_theta > 0)) return 0;
    return distribution_.pdf(p) / (2 * kPi * kPi * sin_theta);
}

Point2 EnvironmentMap::invert(const Vec3& w) const {
    return distribution_.invert(to_map_point(w));
}

std::size_t EnvironmentMap::memory_bytes() const {
    return sizeof(*this) + rgb_.capacity() * sizeof(float) + distribution_.memory_bytes();
}

Light make_environment_light(std::shared_ptr<const EnvironmentMap> map) {
    if (!map) throw std::invalid_argument("world image: no map");
    Light l = make_world_light(map->mean_radiance());
    l.environment = std::move(map);
    return l;
}

}  // namespace omis
