// A square of the floor z = 0 as a texel's footprint: what the tests of
// per-texel set-up, texel tables and footprint strata shade.
#pragma once

#include "render/direct_lighting.h"

namespace omis::testing {

// The square of half side `half` around `centre` (on z = 0), facing +z.
class SquareFootprint : public Footprint {
public:
    SquareFootprint(const Vec3& centre, double half) : centre_(centre), half_(half) {}
    SurfacePoint at(double u, double v) const override {
        const Vec3 x = centre_ + Vec3((2 * u - 1) * half_, (2 * v - 1) * half_, 0);
        return SurfacePoint{x, Vec3(0, 0, 1), Vec3(0, 0, 1)};
    }
    SurfacePoint centre() const { return at(0.5, 0.5); }

private:
    Vec3 centre_;
    double half_;
};

}  // namespace omis::testing
