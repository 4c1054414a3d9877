#include "bake/uv_raster.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

namespace omis {
namespace {

struct P2 {
    double x, y;
};

// Edge function of p against edge a→b, computed on the lexicographically
// ordered end points and negated for the other direction: two triangles that
// share an edge get exactly opposite values.
double edge_function(const P2& a, const P2& b, const P2& p, bool& top_left) {
    const bool forward = (a.x < b.x) || (a.x == b.x && a.y < b.y);
    const P2& lo = forward ? a : b;
    const P2& hi = forward ? b : a;
    const double e = (hi.x - lo.x) * (p.y - lo.y) - (hi.y - lo.y) * (p.x - lo.x);
    // For a counter-clockwise triangle, points on edge a→b count when the edge
    // runs downward, or leftward-horizontal... any fixed half of the
    // directions works; the reverse edge then gets the other half.
    const double dx = b.x - a.x, dy = b.y - a.y;
    top_left = dy < 0 || (dy == 0 && dx > 0);
    return forward ? e : -e;
}

}  // namespace

UvCoverage rasterize_uv(const Mesh& mesh, int width, int height) {
    if (!mesh.has_uvs())
        throw std::invalid_argument("mesh '" + mesh.name + "': has no UV map to bake into");
    if (width < 1 || height < 1)
        throw std::invalid_argument("size: width and height must be positive, got " +
                                    std::to_string(width) + "×" + std::to_string(height));
    if (double(width) * height > double(1u << 30))
        throw std::invalid_argument("size: " + std::to_string(width) + "×" +
                                    std::to_string(height) + " texels is beyond what omis bakes");
    UvCoverage c;
    c.width = width;
    c.height = height;
    const std::size_t texels = std::size_t(width) * height;
    c.triangle.assign(texels, kNoTriangle);
    c.b1.assign(texels, 0.f);
    c.b2.assign(texels, 0.f);

    for (std::uint32_t t = 0; t < mesh.num_triangles(); ++t) {
        P2 v[3];
        for (int k = 0; k < 3; ++k) {
            const auto& uv = mesh.corner_uvs[3 * t + k];
            v[k] = {uv[0] * width, uv[1] * height};
        }
        const double area2 = (v[1].x - v[0].x) * (v[2].y - v[0].y) -
                             (v[1].y - v[0].y) * (v[2].x - v[0].x);
        if (!(std::abs(area2) > 0) || !std::isfinite(area2)) {
            ++c.degenerate_uv_triangles;
            continue;
        }
        // Visit vertices counter-clockwise; remember which original corner is which.
        int order[3] = {0, 1, 2};
        if (area2 < 0) std::swap(order[1], order[2]);
        const P2 a = v[order[0]], b = v[order[1]], d = v[order[2]];

        const int x0 = std::max(0, int(std::floor(std::min({a.x, b.x, d.x}) - 0.5)));
        const int x1 = std::min(width - 1, int(std::ceil(std::max({a.x, b.x, d.x}) - 0.5)));
        const int y0 = std::max(0, int(std::floor(std::min({a.y, b.y, d.y}) - 0.5)));
        const int y1 = std::min(height - 1, int(std::ceil(std::max({a.y, b.y, d.y}) - 0.5)));
        for (int y = y0; y <= y1; ++y) {
            for (int x = x0; x <= x1; ++x) {
                const P2 p{x + 0.5, y + 0.5};
                bool tl0, tl1, tl2;
                const double e0 = edge_function(b, d, p, tl0);  // opposite a
                const double e1 = edge_function(d, a, p, tl1);  // opposite b
                const double e2 = edge_function(a, b, p, tl2);  // opposite d
                if (e0 < 0 || e1 < 0 || e2 < 0) continue;
                if ((e0 == 0 && !tl0) || (e1 == 0 && !tl1) || (e2 == 0 && !tl2)) continue;
                const double sum = e0 + e1 + e2;
                double w[3];
                w[order[0]] = e0 / sum;
                w[order[1]] = e1 / sum;
                w[order[2]] = e2 / sum;
                const std::size_t texel = std::size_t(y) * width + x;
                if (c.triangle[texel] != kNoTriangle)
                    ++c.overlapping_texels;
                else
                    ++c.covered;
                c.triangle[texel] = t;
                c.b1[texel] = float(w[1]);
                c.b2[texel] = float(w[2]);
            }
        }
    }
    return c;
}

namespace {

// Mirror repeat into [0, max]: a coordinate past the triangle's edge comes back
// inside instead of piling up on the edge (as Cycles' bake_clamp_mirror_repeat).
double mirror_clamp(double u, double max) {
    if (!(max > 0)) return 0;
    const double t = u / max, whole = std::floor(t), frac = t - whole;
    return (static_cast<long long>(whole) & 1 ? 1 - frac : frac) * max;
}

}  // namespace

TexelFootprintMap::TexelFootprintMap(const Mesh& mesh, const UvCoverage& cov, std::size_t texel)
    : triangle_(cov.triangle.at(texel)) {
    if (triangle_ == kNoTriangle)
        throw std::invalid_argument("texel: " + std::to_string(texel) + " is not covered");
    // As Cycles: a and b are the weights of corners 0 and 1 (corner 2 is the
    // origin). Their derivatives per texel step are the inverse of the UV
    // triangle's Jacobian in texel units, halved as Blender's
    // bake_differentials does (so the box is half a texel wide).
    a_ = 1.0 - double(cov.b1[texel]) - double(cov.b2[texel]);
    b_ = cov.b1[texel];
    const auto& uv0 = mesh.corner_uvs[3 * triangle_];
    const auto& uv1 = mesh.corner_uvs[3 * triangle_ + 1];
    const auto& uv2 = mesh.corner_uvs[3 * triangle_ + 2];
    const double e0x = (uv0[0] - uv2[0]) * cov.width, e0y = (uv0[1] - uv2[1]) * cov.height;
    const double e1x = (uv1[0] - uv2[0]) * cov.width, e1y = (uv1[1] - uv2[1]) * cov.height;
    const double scale = kTexelFootprintScale / (e0x * e1y - e0y * e1x);  // non-zero: covers a centre
    dadx_ = e1y * scale;
    dady_ = -e1x * scale;
    dbdx_ = -e0y * scale;
    dbdy_ = e0x * scale;
}

std::array<double, 2> TexelFootprintMap::barycentrics(double u, double v) const {
    const double a = mirror_clamp(a_ + dadx_ * (u - 0.5) + dady_ * (v - 0.5), 1.0);
    const double b = mirror_clamp(b_ + dbdx_ * (u - 0.5) + dbdy_ * (v - 0.5), 1.0 - a);
    return {b, std::max(0.0, 1.0 - a - b)};
}

std::vector<std::int64_t> margin_sources(const UvCoverage& c, int margin) {
    const int W = c.width, H = c.height;
    std::vector<std::int64_t> source(std::size_t(W) * H, -1);
    std::vector<std::size_t> frontier, next;
    for (std::size_t i = 0; i < source.size(); ++i)
        if (c.is_covered(i)) {
            source[i] = std::int64_t(i);
            frontier.push_back(i);
        }
    auto distance2 = [&](std::size_t a, std::int64_t b) {
        const double dx = double(a % W) - double(b % W), dy = double(a / W) - double(b / W);
        return dx * dx + dy * dy;
    };
    for (int ring = 0; ring < margin && !frontier.empty(); ++ring) {
        next.clear();
        // Candidates of this ring take the nearest source among their filled
        // neighbours; sources are fixed only after the whole ring is scanned so
        // the result does not depend on scan order.
        std::vector<std::pair<std::size_t, std::int64_t>> fills;
        for (std::size_t f : frontier) {
            const int fx = int(f % W), fy = int(f / W);
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int x = fx + dx, y = fy + dy;
                    if ((dx == 0 && dy == 0) || x < 0 || y < 0 || x >= W || y >= H) continue;
                    const std::size_t t = std::size_t(y) * W + x;
                    if (source[t] >= 0) continue;
                    fills.emplace_back(t, source[f]);
                }
        }
        std::sort(fills.begin(), fills.end());
        for (std::size_t i = 0; i < fills.size();) {
            const std::size_t t = fills[i].first;
            std::int64_t best = fills[i].second;
            for (; i < fills.size() && fills[i].first == t; ++i) {
                const std::int64_t s = fills[i].second;
                const double ds = distance2(t, s), db = distance2(t, best);
                if (ds < db || (ds == db && s < best)) best = s;
            }
            source[t] = best;
            next.push_back(t);
        }
        frontier.swap(next);
    }
    return source;
}

namespace {

// Triangle edges k (corner k to corner k+1) and the triangle across each in 3D.
struct EdgeNeighbours {
    static constexpr std::int64_t kNone = -1;
    std::vector<std::array<std::int64_t, 3>> triangle;   // neighbour or kNone
    std::vector<std::array<std::uint8_t, 3>> corner;     // its corner at our corner k

    explicit EdgeNeighbours(const Mesh& mesh) {
        const std::size_t T = mesh.num_triangles();
        triangle.assign(T, {kNone, kNone, kNone});
        corner.assign(T, {0, 0, 0});
        // Edges with exactly two triangles are shared; more (non-manifold) are not.
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> edges;
        for (std::uint32_t t = 0; t < T; ++t)
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
                if (a != b) edges[{std::min(a, b), std::max(a, b)}].push_back(3 * t + k);
            }
        for (const auto& entry : edges) {
            if (entry.second.size() != 2) continue;
            for (int side = 0; side < 2; ++side) {
                const std::uint32_t self = entry.second[side], other = entry.second[1 - side];
                const std::uint32_t t = self / 3, o = other / 3;
                const std::uint32_t vk = mesh.triangles[t][self % 3];
                int c = 0;
                while (c < 3 && mesh.triangles[o][c] != vk) ++c;
                triangle[t][self % 3] = o;
                corner[t][self % 3] = std::uint8_t(c);
            }
        }
    }
};

struct Carried {
    P2 point;                 // texel coordinates in the neighbour's UV triangle
    std::int64_t triangle;    // the neighbour
    double distance;          // of the original point from the crossed edge, texels
};

P2 texel_uv(const Mesh& mesh, const UvCoverage& c, std::uint32_t t, int corner) {
    const auto& uv = mesh.corner_uvs[3 * t + corner];
    return {uv[0] * c.width, uv[1] * c.height};
}

double cross(const P2& a, const P2& b, const P2& p) {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// The edge of triangle t nearest to p that p lies beyond (projecting inside
// the edge's span), carried across to the triangle sharing that edge in 3D.
bool carry_across(const Mesh& mesh, const UvCoverage& c, const EdgeNeighbours& nb,
                  std::uint32_t t, const P2& p, Carried& out) {
    int best = -1;
    double best_d = 0, best_s = 0;
    for (int k = 0; k < 3; ++k) {
        const P2 a = texel_uv(mesh, c, t, k), b = texel_uv(mesh, c, t, (k + 1) % 3);
        const P2 opposite = texel_uv(mesh, c, t, (k + 2) % 3);
        const double ex = b.x - a.x, ey = b.y - a.y, len2 = ex * ex + ey * ey;
        if (!(len2 > 0)) continue;
        const double s = ((p.x - a.x) * ex + (p.y - a.y) * ey) / len2;
        if (s < 0 || s > 1) continue;
        const double side_p = cross(a, b, p), side_in = cross(a, b, opposite);
        if (side_p == 0 || (side_p > 0) == (side_in > 0)) continue;  // not beyond this edge
        const double d = std::abs(side_p) / std::sqrt(len2);
        if (best < 0 || d < best_d) best = k, best_d = d, best_s = s;
    }
    if (best < 0 || nb.triangle[t][best] == EdgeNeighbours::kNone) return false;
    const std::uint32_t o = std::uint32_t(nb.triangle[t][best]);
    // The shared vertices in the neighbour: ours k → its ca, ours k+1 → its cb.
    const int ca = nb.corner[t][best];
    int cb = 0;
    const std::uint32_t vb = mesh.triangles[t][(best + 1) % 3];
    while (cb < 3 && mesh.triangles[o][cb] != vb) ++cb;
    if (cb == 3 || cb == ca) return false;
    const P2 a2 = texel_uv(mesh, c, o, ca), b2 = texel_uv(mesh, c, o, cb);
    const P2 in2 = texel_uv(mesh, c, o, 3 - ca - cb);
    const double ex = b2.x - a2.x, ey = b2.y - a2.y, len = std::sqrt(ex * ex + ey * ey);
    if (!(len > 0)) return false;
    P2 normal{-ey / len, ex / len};
    if ((in2.x - a2.x) * normal.x + (in2.y - a2.y) * normal.y < 0)
        normal = {-normal.x, -normal.y};
    out.point = {a2.x + best_s * ex + best_d * normal.x, a2.y + best_s * ey + best_d * normal.y};
    out.triangle = o;
    out.distance = best_d;
    return true;
}

bool same_uv_edge(const Mesh& mesh, std::uint32_t t, int k, std::uint32_t o, int ca) {
    // Our corner k+1 against the neighbour's corner holding the same vertex.
    const std::uint32_t vb = mesh.triangles[t][(k + 1) % 3];
    int cb = 0;
    while (cb < 3 && mesh.triangles[o][cb] != vb) ++cb;
    return cb < 3 && mesh.corner_uvs[3 * t + k] == mesh.corner_uvs[3 * o + ca] &&
           mesh.corner_uvs[3 * t + (k + 1) % 3] == mesh.corner_uvs[3 * o + cb];
}

// Where the margin texel at p takes its value from, starting at the island
// triangle t nearest to it; -1 when no adjacent face gives one.
std::int64_t adjacent_source(const Mesh& mesh, const UvCoverage& c, const EdgeNeighbours& nb,
                             std::uint32_t t, const P2& p) {
    Carried carried;
    bool found = carry_across(mesh, c, nb, t, p, carried);
    if (!found) {
        // p may lie beyond a corner of t: try t's neighbours in the same island
        // (sharing the edge's UVs too), nearest crossed edge first.
        double best = 0;
        for (int k = 0; k < 3; ++k) {
            const std::int64_t o = nb.triangle[t][k];
            if (o == EdgeNeighbours::kNone || !same_uv_edge(mesh, t, k, std::uint32_t(o),
                                                            nb.corner[t][k]))
                continue;
            Carried candidate;
            if (carry_across(mesh, c, nb, std::uint32_t(o), p, candidate) &&
                (!found || candidate.distance < best)) {
                carried = candidate, best = candidate.distance, found = true;
            }
        }
    }
    // The carried point must land on a texel of the neighbour (or of a triangle
    // next to it); else, from there, cross on (a few steps, as Blender does).
    for (int step = 0; found && step < 4; ++step) {
        const int x = int(std::floor(carried.point.x)), y = int(std::floor(carried.point.y));
        if (x < 0 || y < 0 || x >= c.width || y >= c.height) return -1;
        const std::size_t texel = std::size_t(y) * c.width + x;
        const std::uint32_t landed = c.triangle[texel];
        const std::int64_t o = carried.triangle;
        if (landed != kNoTriangle &&
            (landed == o || nb.triangle[o][0] == landed || nb.triangle[o][1] == landed ||
             nb.triangle[o][2] == landed))
            return std::int64_t(texel);
        const P2 from = carried.point;  // (carry_across overwrites `carried`)
        found = carry_across(mesh, c, nb, std::uint32_t(o), from, carried);
    }
    return -1;
}

}  // namespace

std::vector<std::int64_t> adjacent_margin_sources(const UvCoverage& c, const Mesh& mesh,
                                                  int margin) {
    std::vector<std::int64_t> source = margin_sources(c, margin);
    if (!mesh.has_uvs() || margin <= 0) return source;
    const EdgeNeighbours nb(mesh);
    const int W = c.width;
    for (std::size_t i = 0; i < source.size(); ++i) {
        if (c.is_covered(i) || source[i] < 0) continue;
        // The island triangle nearest to this margin texel (the Extend source's).
        const std::uint32_t t = c.triangle[std::size_t(source[i])];
        const P2 p{double(i % W) + 0.5, double(i / W) + 0.5};
        const std::int64_t across = adjacent_source(mesh, c, nb, t, p);
        if (across >= 0) source[i] = across;
    }
    return source;
}

}  // namespace omis
