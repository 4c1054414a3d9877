// Issue 32: interpenetrating objects. A point lying inside another closed
// object, or on another object's coinciding face, gets no light from lights
// that cast shadows (Cycles' rays from the point itself are stopped there),
// and the bake counts such texels (BakeStats::buried_texels). Scales from
// millimetres to far from the origin: the contact tolerance follows the
// points' float error, as the ray offset does.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "bake/bake.h"
#include "lights/light.h"
#include "scene/surface_contacts.h"

using namespace omis;

namespace {

// An axis-aligned box [lo, hi] with outward winding and per-corner UVs: each
// face a 3 × 2 atlas cell (inset by 2 %), as a Blender cube's own layout.
struct Box {
    std::vector<Vec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    std::vector<double> uvs;  // 3T × 2
};

Box make_box(const Vec3& lo, const Vec3& hi) {
    Box b;
    const Vec3 c = (lo + hi) / 2.0, h = (hi - lo) / 2.0;
    // (normal, u axis, v axis) with cross(u, v) = normal: outward winding.
    const std::array<std::array<Vec3, 3>, 6> faces = {{
        {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},  {{{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}}},
        {{{0, 1, 0}, {0, 0, 1}, {1, 0, 0}}},  {{{0, -1, 0}, {1, 0, 0}, {0, 0, 1}}},
        {{{0, 0, 1}, {1, 0, 0}, {0, 1, 0}}},  {{{0, 0, -1}, {0, 1, 0}, {1, 0, 0}}},
    }};
    auto scaled = [&](const Vec3& d) { return Vec3{d.x * h.x, d.y * h.y, d.z * h.z}; };
    const std::array<std::array<double, 2>, 4> corners = {{{0, 0}, {1, 0}, {1, 1}, {0, 1}}};
    for (int k = 0; k < 6; ++k) {
        const auto& [n, u, v] = faces[k];
        const auto base = std::uint32_t(b.positions.size());
        for (const auto& q : corners)
            b.positions.push_back(c + scaled(n) + scaled(u) * (2 * q[0] - 1) +
                                  scaled(v) * (2 * q[1] - 1));
        b.triangles.push_back({base, base + 1, base + 2});
        b.triangles.push_back({base, base + 2, base + 3});
        const double ox = (k % 3) / 3.0, oy = (k / 3) / 2.0;
        for (int i : {0, 1, 2, 0, 2, 3})
            b.uvs.insert(b.uvs.end(), {ox + (0.02 + 0.96 * corners[i][0]) / 3,
                                       oy + (0.02 + 0.96 * corners[i][1]) / 2});
    }
    return b;
}

std::uint32_t add_box(Scene& scene, const Box& b, const std::string& name) {
    MeshInput m;
    m.name = name;
    m.positions = ScalarArray::of(&b.positions[0].x, b.positions.size(), 3);
    m.triangles = IndexArray{b.triangles[0].data(), b.triangles.size(), 3};
    m.uvs = ScalarArray::of(b.uvs.data(), b.uvs.size() / 2, 2);
    return scene.add_mesh(m);
}

// Two boxes of one height side by side, overlapping by half, under a point
// light straight above the overlap; lengths `scale`, offset by `origin`.
struct TwoBoxes {
    Scene scene;
    std::uint32_t a = 0, b = 0;
    TwoBoxes(double scale, const Vec3& origin, bool overlap = true) {
        const Vec3 shift{overlap ? 0.5 * scale : 1.5 * scale, 0.3 * scale, 0};
        a = add_box(scene, make_box(origin, origin + Vec3{scale, scale, scale}), "A");
        b = add_box(scene, make_box(origin + shift, origin + shift + Vec3{scale, scale, scale}),
                    "B");
        const Vec3 light = origin + Vec3{0.75 * scale, 0.6 * scale, 4 * scale};
        scene.add_light(make_point_light(light, {1, 1, 1}, 0.0));
        scene.commit();
    }
};

BakeResult bake_box(const Scene& scene, std::uint32_t mesh) {
    BakeSettings s;
    s.mesh = mesh;
    s.width = 48;
    s.height = 32;
    s.margin = 0;
    s.samples = 1;  // a point light: one shadow ray a texel
    return bake(scene, s);
}

}  // namespace

TEST_CASE("coplanar faces of two meshes: a point on the other's face is in contact",
          "[bake][contacts]") {
    TwoBoxes boxes(1.0, {0, 0, 0});
    const SurfaceContacts contacts(boxes.scene.geometry(), boxes.a);
    // A's top (+z, triangles 8 and 9) lies in B's top's plane, its bottom
    // (10, 11) in B's bottom's. Nothing else: B's sides cross A's at right
    // angles.
    CHECK(contacts.triangles_in_contact() == 4);
    using Contact = SurfaceContacts::Contact;
    CHECK(contacts.on_other_surface(8, {0.75, 0.5, 1.0}) == Contact::Facing);
    CHECK(contacts.on_other_surface(8, {0.25, 0.5, 1.0}) == Contact::None);  // beside B
    CHECK(contacts.on_other_surface(0, {1.0, 0.5, 0.5}) == Contact::None);   // A's +x side
    // Within the contact distance above the plane, not beyond it.
    const Vec3 on{0.75, 0.5, 1.0};
    const double d = SurfaceContacts::contact_distance(on);
    CHECK(contacts.on_other_surface(8, on + Vec3{0, 0, 0.5 * d}) == Contact::Facing);
    CHECK(contacts.on_other_surface(8, on + Vec3{0, 0, 2 * d}) == Contact::None);
    // Apart, no box has contacts: the test costs nothing.
    TwoBoxes apart(1.0, {0, 0, 0}, false);
    CHECK_FALSE(SurfaceContacts(apart.scene.geometry(), apart.a).any());
}

TEST_CASE("interpenetrating boxes bake dark inside each other and count those texels",
          "[bake][contacts]") {
    // Millimetres, metres, and a kilometre from the origin (float spacing
    // 6e-5 m there): the contact tolerance and the ray offset scale alike.
    struct Where {
        double scale;
        Vec3 origin;
    };
    for (const Where& w : {Where{1.0, {0, 0, 0}}, Where{1e-3, {0, 0, 0}},
                           Where{1.0, {1000, -700, 300}}}) {
        INFO("scale " << w.scale << ", origin " << w.origin.x);
        TwoBoxes boxes(w.scale, w.origin);
        for (std::uint32_t mesh : {boxes.a, boxes.b}) {
            const BakeResult r = bake_box(boxes.scene, mesh);
            const Mesh& m = boxes.scene.geometry().mesh(mesh);
            const Vec3 other_lo = w.origin + (mesh == boxes.a ? Vec3{0.5, 0.3, 0} : Vec3{0, 0, 0}) * w.scale;
            const Vec3 other_hi = other_lo + Vec3{w.scale, w.scale, w.scale};
            // Texels whose centre lies inside the other box or on its faces
            // (closed box), a margin of a texel's footprint away from its rim.
            const UvCoverage cov = rasterize_uv(m, r.width, r.height);
            std::size_t inside = 0, lit_inside = 0;
            const double margin = 0.05 * w.scale;
            for (std::size_t i = 0; i < cov.triangle.size(); ++i) {
                if (!cov.is_covered(i)) continue;
                const Vec3 p = m.position(cov.triangle[i], cov.b1[i], cov.b2[i]);
                const bool in = p.x >= other_lo.x + margin && p.x <= other_hi.x - margin &&
                                p.y >= other_lo.y + margin && p.y <= other_hi.y - margin &&
                                p.z >= other_lo.z - 1e-9 * w.scale && p.z <= other_hi.z + 1e-9 * w.scale;
                if (!in) continue;
                ++inside;
                lit_inside += r.value[3 * i + 1] > 0;
            }
            INFO("mesh " << m.name << ": " << inside << " texels inside the other box");
            CHECK(inside > 100);
            CHECK(lit_inside == 0);
            // Counted: those, and the ones nearer the rim (up to the coverage).
            CHECK(r.stats.buried_texels >= inside);
            CHECK(r.stats.buried_texels <= r.stats.covered);
        }
    }
    // Apart: nothing is buried, and the tops are lit.
    TwoBoxes apart(1.0, {0, 0, 0}, false);
    const BakeResult r = bake_box(apart.scene, apart.a);
    CHECK(r.stats.buried_texels == 0);
}
