// Light shape draws at a shading position and their densities: a light's
// point drawn by its technique's sampler (solid angle, area, ...), the
// per-position spherical shapes that draws and densities share, and the last
// draw, whose density is reused. Internal to the lighting core (render/*.cpp).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "render/direct_lighting.h"
#include "sampling/ellipse.h"
#include "sampling/spherical.h"

namespace omis {

// A triangle light's hit test along a direction, once made (or not).
struct TriangleTest {
    bool known = false;
    std::optional<ShapeHit> hit;
};

class ShapeDraws {
public:
    explicit ShapeDraws(const LightingContext& context);

    // A new shading position: the per-position shapes are made again.
    void new_position() { ++position_; }
    // Light l's point drawn by `sampler` from x (normal n); remembered as the
    // last draw.
    std::optional<LightSample> sample(std::uint32_t l, ShapeSampler sampler, const Vec3& x,
                                      const Vec3& n, double u1, double u2);
    // Light l's density along w for `sampler` (solid angle measure). known:
    // its triangle's hit test along w, where made (LightsAlong::tests).
    double pdf(std::uint32_t l, ShapeSampler sampler, const Vec3& x, const Vec3& n,
               const Vec3& w, const TriangleTest* known = nullptr);
    // The light of the last draw, where it was drawn toward w (~0u otherwise).
    std::uint32_t last_light_toward(const Vec3& w) const {
        return last_.light != ~0u && last_.w.x == w.x && last_.w.y == w.y && last_.w.z == w.z
                   ? last_.light
                   : ~0u;
    }

private:
    // Spherical rectangles/triangles and elliptic cones depend on the position
    // only: build each once per position instead of once per sample and pdf
    // evaluation (an ellipse's cone takes a Jacobi orthogonalisation: 39 % of a
    // spread-disk bake when built per evaluation). Skipped for scenes with
    // very many lights, where the table would not pay.
    struct SolidAngleCache {
        std::uint64_t point = ~0ull;
        Vec3 n;  // the receiver normal the warp was made for
        std::optional<CosineWarped<SphericalRect>> rect;
        std::optional<CosineWarped<SphericalTriangle>> triangle;
        std::optional<SphericalEllipse> ellipse;
    };
    static constexpr std::size_t kMaxCachedLights = 1024;
    const SolidAngleCache* solid_angle(std::uint32_t l, const Vec3& x, const Vec3& n);
    bool solid_angle_ready(std::uint32_t l) const {
        return l < solid_angle_cache_.size() && solid_angle_cache_[l].point == position_;
    }
    static std::optional<LightSample> sample_cached(const SolidAngleCache& c, double u1,
                                                    double u2);
    // Whether light l (`light`) is tiny in solid angle at x (kTinySolidAngle).
    bool tiny(std::uint32_t l, const Light& light, const Vec3& x) const;
    // `sampler`: the technique's, before the tiny-light substitution (the
    // draw made it for the same light and point).
    bool last_density(std::uint32_t l, ShapeSampler sampler, const Vec3& w, double& pdf) const {
        if (!reuse_last_pdf_ || last_.light != l || last_.point != position_ ||
            last_.sampler != sampler || last_.w.x != w.x || last_.w.y != w.y || last_.w.z != w.z)
            return false;
        pdf = last_.pdf;
        return true;
    }

    const LightingContext& context_;
    std::vector<SolidAngleCache> solid_angle_cache_;
    std::uint64_t position_ = 0;  // counts the positions shaded
    // The last light sample: its light surely lies along its direction, and
    // its shape density there is the one the draw returned — pdf() reuses it
    // instead of inverting the draw (~10 % of a solid-angle sample) where the
    // weights are continuous in the densities (reuse_last_pdf_), so that a
    // last-digit difference from the evaluated density changes nothing. The
    // maximum and cutoff heuristics compare densities (exact ties where two
    // techniques share a density), so there every density stays one function
    // of the direction, whichever technique drew it.
    struct LastDraw {
        std::uint32_t light = ~0u;
        Vec3 w;
        // The technique's (a tiny light's draw used Area: pdf() repeats the
        // choice from the light and the point).
        ShapeSampler sampler = ShapeSampler::Area;
        double pdf = 0;
        std::uint64_t point = ~0ull;  // position_ of the draw
    } last_;
    const bool reuse_last_pdf_;
};

}  // namespace omis
