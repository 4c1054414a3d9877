// Where a bake shades: a covered texel's footprint (positions and normals
// over the texel) and the points of a mesh's triangle corners, each moved
// behind another mesh's face it lies on.
#pragma once

#include <cstdint>
#include <vector>

#include "bake/uv_raster.h"
#include "render/direct_lighting.h"
#include "scene/surface_contacts.h"

namespace omis::bake_detail {

// A point of triangle t that lies on another mesh's face has its rays stopped
// there, as Cycles' do (scene/surface_contacts.h): it is moved behind both.
SurfacePoint on_contact(SurfacePoint p, std::uint32_t t, const SurfaceContacts* contacts);

// A covered texel's footprint as a Footprint: positions and normals at the
// barycentrics of texel_footprint (uv_raster.h).
class TexelFootprint final : public Footprint {
public:
    TexelFootprint(const Mesh& mesh, const UvCoverage& cov, std::size_t i, bool smooth,
                   const SurfaceContacts* contacts = nullptr)
        : mesh_(mesh), cov_(cov), i_(i), map_(mesh, cov, i),
          ng_(mesh.geometric_normal(map_.triangle())), smooth_(smooth), contacts_(contacts) {}

    SurfacePoint at(double u, double v) const override {
        const auto b = map_.barycentrics(u, v);
        return point(b[0], b[1]);
    }
    SurfacePoint centre() const { return at(0.5, 0.5); }

    // The texels of a kAnchorBlock² block share their light tables' weights,
    // measured at the centre of one texel near the block's middle, when that
    // texel lies on the same triangle (else each texel is weighed alone).
    bool table_anchor(Anchor& anchor) const override {
        const std::size_t w = std::size_t(cov_.width), h = std::size_t(cov_.height);
        const std::size_t x = i_ % w, y = i_ / w;
        const std::size_t ax = std::min(w - 1, x / kAnchorBlock * kAnchorBlock + kAnchorBlock / 2);
        const std::size_t ay = std::min(h - 1, y / kAnchorBlock * kAnchorBlock + kAnchorBlock / 2);
        const std::size_t a = ay * w + ax;
        if (cov_.triangle[a] != map_.triangle()) return false;
        anchor.id = a;
        anchor.at = point(cov_.b1[a], cov_.b2[a]);
        return true;
    }

private:
    SurfacePoint point(double b1, double b2) const {
        const std::uint32_t t = map_.triangle();
        Vec3 n = smooth_ ? mesh_.shading_normal(t, b1, b2) : ng_;
        if (!(length(n) > 0)) n = ng_;
        return on_contact({mesh_.position(t, b1, b2), n, ng_}, t, contacts_);
    }

    // 4² texels a measurement: a 16th of the weights' cost (the spread and
    // round lights' dominated a one-sample pass), while the weights move by
    // what light changes over 4 texels.
    static constexpr std::size_t kAnchorBlock = 4;
    const Mesh& mesh_;
    const UvCoverage& cov_;
    std::size_t i_;
    TexelFootprintMap map_;
    Vec3 ng_;
    bool smooth_;
    const SurfaceContacts* contacts_;  // the receiver's contacts (issue 32), if any
};

// One point per triangle corner, inside its triangle as Cycles places it
// (vertex bakes are reduced from corners: see vertex_points.h).
std::vector<SurfacePoint> corner_points(const Mesh& mesh, bool smooth);

}  // namespace omis::bake_detail
