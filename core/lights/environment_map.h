// An image-based world: an equirectangular RGB radiance map with a rotation,
// in Blender / Cycles' convention, and its importance sampling.
//
// Convention (Cycles, kernel/camera/projection.h, direction_to_equirectangular:
// u = (atan2(d.y, d.x) − π)/(−2π), v = (acos(d.z) − π)/(−π)): the image's
// horizontal centre looks along +X, u grows from +X toward −Y, and v = 1 is
// the zenith (+Z). Rows are stored top first (row 0 at the zenith, as image
// files and numpy arrays hold them; Blender's own pixel buffers are bottom
// first). The Mapping node's rotation (Euler XYZ, R = Rz·Ry·Rx, Cycles'
// euler_to_transform) turns the world direction ω before the lookup: the
// radiance from ω is the texel at R·ω.
//
// Texels are piecewise constant (closest lookup): the map is the world's
// radiance averaged over each texel. Draws come from a 2-D piecewise-constant
// distribution over (u, θ/π) weighted by luminance × the row's mean sin θ
// (pbrt-v4's ImageInfiniteLight, Cycles' background map), with the exact
// density in solid angle p(u, t) / (2π² sin θ). With `compensate` the
// weights are max(0, luminance − mean) (Karlík et al. 2019, MIS
// compensation), for use beside a technique that covers the rest.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "math/vec3.h"
#include "sampling/distribution_2d.h"
#include "sampling/shapes.h"

namespace omis {

class EnvironmentMap {
  public:
    // rgb: width × height × 3 floats, rows top first; every value finite and
    // ≥ 0. rotation: Euler XYZ angles in radians. Throws
    // std::invalid_argument naming the first bad texel or argument.
    EnvironmentMap(std::vector<float> rgb, int width, int height, const Vec3& rotation,
                   bool compensate);

    // Radiance arriving from direction w (unit, world space).
    Vec3 radiance(const Vec3& w) const;
    // A world-space direction drawn from the map's distribution, with its
    // solid-angle pdf (sr⁻¹); empty only for a draw onto a pole (measure 0).
    std::optional<LightSample> sample(double u1, double u2) const;
    // Solid-angle density (sr⁻¹) of sample() at w.
    double pdf(const Vec3& w) const;
    // The (u1, u2) that sample() maps to w.
    Point2 invert(const Vec3& w) const;

    // ∫ L dω over the sphere, per channel (W/m² ... per steradian integrated).
    const Vec3& integral() const { return integral_; }
    // The radiance of the constant world with the same integral: ∫ L dω / 4π.
    Vec3 mean_radiance() const { return integral_ / (4 * kPi); }

    // What the map was made from (a scene snapshot stores these).
    int width() const { return width_; }
    int height() const { return height_; }
    const std::vector<float>& rgb() const { return rgb_; }
    const Vec3& rotation() const { return rotation_; }
    bool compensated() const { return compensate_; }
    // Whether compensation found anything above the mean (else the plain
    // distribution is used, as for a constant map).
    bool compensation_applied() const { return compensation_applied_; }
    std::size_t memory_bytes() const;

    // Cycles' equirectangular mapping of a map-space unit direction to (u, v)
    // in [0, 1)² (v = 1 at +Z), and back.
    static Point2 direction_to_equirectangular(const Vec3& d);
    static Vec3 equirectangular_to_direction(const Point2& uv);

  private:
    int width_ = 0, height_ = 0;
    std::vector<float> rgb_;
    Vec3 rotation_;
    bool compensate_ = false, compensation_applied_ = false;
    std::array<Vec3, 3> to_map_;  // rows of R: map direction = R·w
    Vec3 integral_;
    PiecewiseConstant2D distribution_;  // over (u, θ/π), rows top first

    // The distribution's point (u, θ/π) of a world direction, and back.
    Point2 to_map_point(const Vec3& w) const;
    Vec3 from_map_point(const Point2& p, double* sin_theta) const;
    Vec3 texel(int column, int row) const;
};

// A world light radiating the map (its power and selection weights use the
// map's mean radiance; Scene::add_light keeps one world).
struct Light;
Light make_environment_light(std::shared_ptr<const EnvironmentMap> map);

}  // namespace omis
