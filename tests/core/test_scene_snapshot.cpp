// Scene snapshots (io/scene_snapshot.h): a loaded scene bakes the bits of the
// scene saved, and every damaged file — cut at any length, any byte flipped,
// counts beyond the file — is refused with SnapshotError, never read out of
// bounds (the sanitizer build runs this too) nor allocated for from a count.
#include <catch2/catch.hpp>

#include <cstring>
#include <stdexcept>
#include <vector>

#include "bake/bake.h"
#include "io/scene_snapshot.h"
#include "render/scene.h"

using namespace omis;

namespace {

// A floor with UVs and normals under a rect light, a box, a spot and a world.
void build(Scene& scene) {
    const std::vector<double> positions = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    const std::vector<std::uint32_t> triangles = {0, 1, 2, 0, 2, 3};
    const std::vector<double> uvs = {0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 1};
    std::vector<double> normals;
    for (int c = 0; c < 6; ++c) normals.insert(normals.end(), {0.0, 0.05, 1.0});
    MeshInput floor;
    floor.name = "floor";
    floor.positions = ScalarArray::of(positions.data(), 4, 3);
    floor.triangles = {triangles.data(), 2, 3};
    floor.uvs = ScalarArray::of(uvs.data(), 6, 2);
    floor.normals = ScalarArray::of(normals.data(), 6, 3);
    scene.add_mesh(floor);
    scene.add_mesh({{0.2, 0.2, 0.3}, {0.5, 0.2, 0.3}, {0.5, 0.5, 0.3}}, {{{0, 1, 2}}},
                   Vec3(1, 2, 3));
    scene.set_mesh_receiver(0, make_receiver(ReceiverModel::OrenNayar, 0.5));
    scene.add_light(make_rect_light({-0.5, -0.5, 1}, {0, 1, 0}, {1, 0, 0}, {2, 2, 2}, false, 2.0));
    scene.add_light(make_spot_light({0.5, 0, 1}, {0, 0, -1}, {5, 5, 5}, 0.05, 1.0, 0.2));
    scene.add_light(make_world_light({0.1, 0.1, 0.2}));
    scene.set_light_flags(1, false, true);
}

std::vector<float> bake_values(const Scene& scene) {
    BakeSettings s;
    s.width = s.height = 12;
    s.samples = 4;
    s.lighting.seed = 5;
    return bake(scene, s).value;
}

bool refused(const std::vector<unsigned char>& bytes) {
    Scene scene;
    try {
        load_snapshot(bytes.data(), bytes.size(), scene);
    } catch (const SnapshotError&) {
        return true;
    } catch (const std::invalid_argument&) {
        return true;  // a value the scene's setters refuse
    }
    return false;
}

}  // namespace

TEST_CASE("a loaded snapshot bakes the bits of the scene saved", "[snapshot]") {
    Scene scene;
    build(scene);
    const std::vector<unsigned char> before_commit = save_snapshot(scene);
    scene.commit();
    const std::vector<unsigned char> bytes = save_snapshot(scene);
    CHECK(bytes == before_commit);  // commit's lights are made again, not stored
    Scene loaded;
    load_snapshot(bytes.data(), bytes.size(), loaded);
    CHECK(loaded.committed());
    CHECK(loaded.geometry().mesh(0).name == "floor");
    CHECK(loaded.lights().size() == scene.lights().size());
    CHECK(bake_values(loaded) == bake_values(scene));
    CHECK(save_snapshot(loaded) == bytes);
    CHECK_THROWS_AS(load_snapshot(bytes.data(), bytes.size(), loaded), std::logic_error);
}

TEST_CASE("damaged snapshots are refused at every length and every byte", "[snapshot]") {
    Scene scene;
    build(scene);
    const std::vector<unsigned char> bytes = save_snapshot(scene);
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        const std::vector<unsigned char> cut(bytes.begin(), bytes.begin() + n);
        INFO("cut at " << n);
        CHECK(refused(cut));
    }
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        std::vector<unsigned char> flipped = bytes;
        flipped[i] ^= std::uint8_t(1u << (i % 8));
        INFO("byte " << i);
        CHECK(refused(flipped));
    }
}

TEST_CASE("crc32 is zlib's", "[snapshot]") {
    const char* text = "123456789";
    CHECK(crc32(reinterpret_cast<const unsigned char*>(text), 9) == 0xCBF43926u);
}
