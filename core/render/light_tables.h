// Per-point light tables: for each light technique that draws from a table
// (not from one of the context's selectors), the lights it may pick at a
// point or over a footprint's probes, with their probabilities and CDF; the
// `defensive` mixture; the `unoccluded` weights a block of texels measures
// once at its anchor. Internal to the lighting core (render/*.cpp).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "render/direct_lighting.h"
#include "sampling/discrete.h"

namespace omis {

// Where each technique's cells lie in a per-point record that keeps
// `cells` of them for every technique that draws from a per-point table (not
// `bsdf`, not from a selector): their offsets, ~0 for the other techniques.
std::vector<std::size_t> table_technique_offsets(const LightingContext& context,
                                                 std::size_t cells);

// A light technique's table at one point: the lights it may pick (in the
// context's integrated order) and their probabilities and CDF.
struct LightTable {
    std::vector<std::uint32_t> lights;
    std::vector<double> probability, cdf;
    // The slot a selection draw u ∈ [0, 1) picks.
    int slot(double u) const {
        return int(std::min<std::size_t>(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin(),
                                         lights.size() - 1));
    }
};

// A footprint's probes for its tables and region: the centre, and its
// corners made only when first asked (most lights reach the centre, and
// then no corner is looked at).
class FootprintProbes {
public:
    FootprintProbes(const SurfacePoint& centre, const Footprint* footprint)
        : footprint_(footprint), corners_ready_(!footprint) {
        p_[0] = centre;
    }
    int count() const { return footprint_ ? 5 : 1; }
    const SurfacePoint& operator[](int i) {
        if (i > 0 && !corners_ready_) {
            int j = 1;
            for (double u : {0.0, 1.0})
                for (double v : {0.0, 1.0}) p_[j++] = footprint_->at(u, v);
            corners_ready_ = true;
        }
        return p_[i];
    }

private:
    const Footprint* footprint_;
    bool corners_ready_;
    SurfacePoint p_[5];
};

// The tables of one shading thread, per technique (light techniques only),
// remade at every point (or restored from a texel's kept ones).
class LightTables {
public:
    explicit LightTables(const LightingContext& context)
        : context_(context), tables_(context.settings.techniques.size()) {}

    const LightTable& operator[](int k) const { return tables_[std::size_t(k)]; }
    // The longest table's size.
    std::size_t longest() const;

    // Whether technique k has a light to draw at (x, n). `tree` (and
    // `uniform`, `power` among many lights) draws from the context's
    // selectors, which need no per-point table; otherwise technique k's table
    // over the lights that reach x is made here (`unoccluded`: by their exact
    // unoccluded irradiance). A technique with no light to draw at x leaves
    // the point's MIS system.
    bool make_at(int k, const Vec3& x, const Vec3& n);
    // make_at's table for a whole footprint (its probes: the centre and
    // corners), so a light that reaches part of a texel keeps its share
    // wherever in the texel it was probed. kept: the point's reach for
    // technique k (LightingContext::table_reach), null where none is kept.
    bool make_over(int k, FootprintProbes& probes, std::uint8_t* kept);
    // Technique k's table as kept (TexelTables), its CDF summed again.
    void restore(int k, const std::vector<std::uint32_t>& lights,
                 const std::vector<double>& probability);
    // The anchor of the footprint being set up (Footprint::table_anchor;
    // null: none): `unoccluded` weights are measured there where it sees the light.
    void set_anchor(const Footprint* footprint);

private:
    void mix_in_uniform(int k);
    double centre_weight(std::size_t i, const SurfacePoint& centre);

    const LightingContext& context_;
    std::vector<LightTable> tables_;
    // Per slot of the table being made, whether its light reaches some probe.
    std::vector<char> reaches_;
    // `unoccluded` weights at the footprint's anchor, shared by the texels of
    // its block: kept for the last kAnchorSlots anchors seen (a tile's row of
    // texels crosses several blocks), per integrated light (index into the
    // context's integrated), NaN until asked.
    struct AnchorWeights {
        bool used = false;
        Footprint::Anchor anchor;
        std::vector<double> irradiance;
    };
    static constexpr int kAnchorSlots = 8;
    AnchorWeights anchors_[kAnchorSlots];
    AnchorWeights* anchor_ = nullptr;  // the footprint being set up's; null: none
    int next_anchor_slot_ = 0;
};

}  // namespace omis
