// The integrated lights a direction from a shading position may cross (a
// superset: area lights from the Embree shape scene, plus the few unshaped
// ones), kept for the direction last asked about, with the triangles' hit
// tests and the shape densities along it. The integrand lists them (or hands
// over the list its closest hit's traversal made); the densities read them.
// Internal to the lighting core (render/*.cpp).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "render/shape_draws.h"

namespace omis {

// Adds light l to `lights` unless it is there (a light drawn toward w surely
// lies along w, even where single precision missed its shape).
inline void add_if_missing(std::vector<std::uint32_t>& lights, std::uint32_t l) {
    if (std::find(lights.begin(), lights.end(), l) == lights.end()) lights.push_back(l);
}

class LightsAlong {
public:
    LightsAlong(const LightingContext& context, ShapeDraws& shapes, LightingCounters& counters)
        : context_(context), shapes_(shapes), counters_(counters) {}

    // Whether the lights along (x, w) are listed already.
    bool listed(const Vec3& x, const Vec3& w) const {
        const Along& a = along_;
        return a.valid && a.x.x == x.x && a.x.y == x.y && a.x.z == x.z && a.w.x == w.x &&
               a.w.y == w.y && a.w.z == w.z;
    }
    // Every integrated light w from x may cross.
    const std::vector<std::uint32_t>& of(const Vec3& x, const Vec3& w);
    // `lights` (every light along (x, w), as a closest hit's traversal found
    // them) becomes the list; `lights` receives the old one's storage.
    const std::vector<std::uint32_t>& adopt(const Vec3& x, const Vec3& w,
                                            std::vector<std::uint32_t>& lights);
    bool is_list(const std::vector<std::uint32_t>* lights) const { return lights == &along_.lights; }
    // The list's hit tests, one per light, for its maker to fill (valid until
    // the next list): the shape's area density takes them instead of a second
    // test (~140 instructions a sample among emissive triangles).
    TriangleTest* begin_tests() {
        along_.tests.resize(along_.lights.size());
        along_.tested = serial_;
        return along_.tests.data();
    }
    // The hit tests of `lights`, where it is the list and they were made; else null.
    const TriangleTest* tests_of(const std::vector<std::uint32_t>& lights) const {
        return &lights == &along_.lights && along_.tested == serial_ ? along_.tests.data()
                                                                      : nullptr;
    }
    // The shape pdf of each light in `along` = of(x, w) (the caller's, got
    // once) for `sampler`: kept for the direction, as techniques that share a
    // sampler (tree/… and power/…) ask for the same values.
    const std::vector<double>& shape_pdfs(const std::vector<std::uint32_t>& along,
                                          ShapeSampler sampler, const Vec3& x, const Vec3& n,
                                          const Vec3& w);

private:
    // A new list, for (x, w): the hit tests and shape densities kept are
    // those of an older one from now on.
    void start_list(const Vec3& x, const Vec3& w) {
        along_.x = x;
        along_.w = w;
        along_.valid = true;
        ++serial_;
    }

    const LightingContext& context_;
    ShapeDraws& shapes_;
    LightingCounters& counters_;
    struct Along {
        Vec3 x, w;
        bool valid = false;
        std::vector<std::uint32_t> lights;
        std::vector<TriangleTest> tests;  // valid while serial_ = tested
        std::uint64_t tested = 0;
    } along_;
    struct ShapePdfs {
        std::uint64_t along = 0;  // serial_ they were evaluated for
        ShapeSampler sampler = ShapeSampler::Area;
        Vec3 n;
        std::vector<double> pdf;  // per light in along_.lights
    } shape_pdfs_;
    std::uint64_t serial_ = 0;  // counts the lists made
};

}  // namespace omis
