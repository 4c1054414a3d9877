// Where a mesh's UV layout puts its triangles in a W×H texture: for every
// texel whose centre ((x + ½)/W, (y + ½)/H) lies in a triangle, that triangle
// and the barycentrics there. Row y = 0 is at v = 0 (the bottom row, as
// Blender stores image pixels).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "scene/geometry_scene.h"

namespace omis {

constexpr std::uint32_t kNoTriangle = 0xFFFFFFFFu;

struct UvCoverage {
    int width = 0, height = 0;
    // Per texel: the covering triangle (kNoTriangle if none) and the
    // barycentrics of its vertices 1 and 2 at the texel centre.
    std::vector<std::uint32_t> triangle;
    std::vector<float> b1, b2;
    std::size_t covered = 0;
    std::size_t degenerate_uv_triangles = 0;  // zero UV area: cannot hold a texel
    std::size_t overlapping_texels = 0;       // claimed by more than one triangle

    bool is_covered(std::size_t texel) const { return triangle[texel] != kNoTriangle; }
};

// The coverage rule: a centre strictly inside a triangle is covered; a centre
// exactly on an edge belongs to exactly one of the two triangles sharing it
// (the top-left rule, evaluated on a canonical ordering of the edge's end
// points so both triangles compute the same number). Hence no cracks and no
// double coverage along shared edges. Throws std::invalid_argument when the
// mesh has no UVs or the size is unusable.
UvCoverage rasterize_uv(const Mesh& mesh, int width, int height);

// Width of a texel's footprint in texels. Blender computes the texel
// differentials it hands to Cycles' bake with a factor ½
// (render/intern/bake.cc, bake_differentials), so Cycles box-filters over
// the central half-texel square; omis follows it to bake the same quantity.
constexpr double kTexelFootprintScale = 0.5;

// A covered texel's footprint, as Cycles' bake samples it
// (kernel/integrator/init_from_bake.h, 3.4): a square around the texel centre
// (kTexelFootprintScale texels wide) through the centre's barycentrics plus
// the differentials times (u − ½, v − ½), mirror-clamped back into the same
// triangle. Unlike Cycles, no sample is forced to the centre, so a mean over
// uniform (u, v) is the box-filtered value at every sample count.
class TexelFootprintMap {
public:
    TexelFootprintMap(const Mesh& mesh, const UvCoverage& coverage, std::size_t texel);
    // (b1, b2) for (u, v) in [0, 1]²; (½, ½) is the texel centre.
    std::array<double, 2> barycentrics(double u, double v) const;
    std::uint32_t triangle() const { return triangle_; }

private:
    std::uint32_t triangle_;
    double a_, b_, dadx_, dady_, dbdx_, dbdy_;  // weights of corners 0 and 1
};

// Extends covered texels into uncovered ones up to `margin` texels away
// (Chebyshev distance, as repeated 8-neighbour dilation), each filled texel
// taking the index of the nearest covered texel (Euclidean) — Cycles'
// "extend" margin. Returns, per texel, the source texel or -1.
std::vector<std::int64_t> margin_sources(const UvCoverage& coverage, int margin);

// How texels in the margin get their values (Blender's Bake ▸ Margin ▸ Type).
enum class MarginType { Extend, AdjacentFaces };

// Blender's "Adjacent Faces" margin: the same texels as margin_sources, but a
// texel beyond an island's border edge takes its value from the triangle on
// the other side of that edge in 3D (sharing its two vertices), wherever UV
// seams put it: the texel's position relative to the edge (parameter along it,
// distance from it) is carried over to the neighbour's UV edge, inwards. Texels
// beyond mesh boundaries, or whose carried position lands on no covered texel
// of the neighbourhood, fall back to the Extend source. Returns, per texel, the
// source texel or -1.
std::vector<std::int64_t> adjacent_margin_sources(const UvCoverage& coverage, const Mesh& mesh,
                                                  int margin);

}  // namespace omis
