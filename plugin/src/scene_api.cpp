// C ABI of scenes (omis.h, "Scenes and direct lighting"; the lighting job is in lighting_api.cpp).
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "api_common.h"
#include "scene_impl.h"
#include "io/image_read.h"
#include "lights/environment_map.h"
#include "render/effect_plan.h"
#include "render/scene.h"
#include "render/techniques.h"

using namespace omis::api;

namespace {

omis::Vec3 vec3(const double* v, const char* name) {
    checked(v, name);
    return {v[0], v[1], v[2]};
}

std::size_t scalar_size(const OMISDataType& data_type) {  // by reference: see enum_value
    const int type = enum_value(data_type);
    switch (type) {
        case OMIS_DATA_FLOAT32:
            return sizeof(float);
        case OMIS_DATA_FLOAT64:
            return sizeof(double);
    }
    throw std::invalid_argument("type: unknown data type " + std::to_string(type) +
                                " (OMIS_DATA_FLOAT32 or OMIS_DATA_FLOAT64)");
}

// A (rows, cols) scalar array for the core, over the caller's memory when it
// is packed and aligned, else over a packed copy kept in `storage`.
omis::ScalarArray scalar_array(const void* data, OMISDataType type,
                               std::size_t byte_stride, std::size_t rows,
                               std::size_t cols, std::vector<unsigned char>& storage) {
    const std::size_t scalar = scalar_size(type);
    const std::size_t row_bytes = scalar * cols;
    if (byte_stride == 0) byte_stride = row_bytes;
    const bool direct =
        byte_stride == row_bytes && reinterpret_cast<std::uintptr_t>(data) % scalar == 0;
    const void* packed = data;
    if (!direct) {
        // Copy with memcpy: strided or unaligned rows cannot be read in place.
        storage.resize(rows * row_bytes);
        const auto* in = static_cast<const unsigned char*>(data);
        for (std::size_t r = 0; r < rows; ++r)
            std::memcpy(storage.data() + r * row_bytes, in + r * byte_stride, row_bytes);
        packed = storage.data();
    }
    if (type == OMIS_DATA_FLOAT32)
        return omis::ScalarArray::of(static_cast<const float*>(packed), rows, cols);
    return omis::ScalarArray::of(static_cast<const double*>(packed), rows, cols);
}

// Adds a light built by a core factory under the build lock.
template <class Make>
unsigned int add_light(OMISScene scene, const char* what, Make&& make) {
    return guarded<unsigned int>(OMIS_INVALID_ID, [&] {
        auto* s = checked(scene, "scene");
        const omis::Light light = make();  // validates before taking the lock
        auto lock = s->lock_for_build(what);
        return static_cast<unsigned int>(s->scene.add_light(light));
    });
}

// Rect and ellipse lights: a point and two perpendicular vectors, each checked
// under its own argument name.
using PlanarFactory = omis::Light (*)(const omis::Vec3&, const omis::Vec3&, const omis::Vec3&,
                                      const omis::Vec3&, bool, double);
unsigned int add_planar_light(OMISScene scene, const char* what, PlanarFactory make,
                              const std::array<const double*, 3>& frame,
                              const std::array<const char*, 3>& names,
                              const double* radiance, bool two_sided, double spread) {
    return add_light(scene, what, [&] {
        return make(vec3(frame[0], names[0]), vec3(frame[1], names[1]),
                    vec3(frame[2], names[2]), vec3(radiance, "radiance"), two_sided, spread);
    });
}

}  // namespace

std::vector<omis::Technique> omis::api::parse_technique_list(const std::string& list) {
    std::vector<omis::Technique> techniques;
    std::size_t begin = 0;
    while (true) {
        const std::size_t end = std::min(list.find(',', begin), list.size());
        std::string name = list.substr(begin, end - begin);
        const auto first = name.find_first_not_of(" \t");
        name = first == std::string::npos
                   ? std::string()
                   : name.substr(first, name.find_last_not_of(" \t") - first + 1);
        if (name.empty())
            throw std::invalid_argument("techniques: empty name in the list '" + list +
                                        "'");
        const auto technique = omis::parse_technique(name);
        if (!technique)
            throw std::invalid_argument("techniques: unknown technique '" + name + "' (" +
                                        omis::technique_grammar() + ")");
        techniques.push_back(*technique);
        if (end == list.size()) break;
        begin = end + 1;
    }
    return techniques;
}

TechniqueChoice omis::api::choose_techniques(const omis::Scene& scene, const char* names,
                                             const int* samples) {
    TechniqueChoice choice;
    if (!names || !*names) {
        omis::default_techniques(scene, choice.techniques, choice.samples);
        return choice;
    }
    choice.techniques = parse_technique_list(names);
    checked(samples, "samples");
    for (std::size_t k = 0; k < choice.techniques.size(); ++k) {
        if (samples[k] < 0)
            throw std::invalid_argument("samples: entry " + std::to_string(k) + " (" +
                                        choice.techniques[k].name() + ") is negative");
        choice.samples.push_back(samples[k]);
    }
    return choice;
}

TechniqueChoice omis::api::choose_techniques(const omis::Scene& scene, const std::string& names,
                                             const std::vector<int>& counts) {
    TechniqueChoice choice;
    if (names.empty()) {
        if (!counts.empty())
            throw std::invalid_argument("counts: given without techniques (no techniques "
                                        "lets the effect plan choose both)");
        omis::default_techniques(scene, choice.techniques, choice.samples);
        return choice;
    }
    choice.techniques = parse_technique_list(names);
    choice.samples = counts.empty() ? std::vector<int>(choice.techniques.size(), 1) : counts;
    if (choice.samples.size() != choice.techniques.size())
        throw std::invalid_argument("counts: expected " +
                                    std::to_string(choice.techniques.size()) +
                                    " entries (one per technique), got " +
                                    std::to_string(counts.size()));
    for (std::size_t k = 0; k < choice.samples.size(); ++k)
        if (choice.samples[k] < 0)
            throw std::invalid_argument("counts: entry " + std::to_string(k) + " (" +
                                        choice.techniques[k].name() + ") is negative");
    return choice;
}

OMIS_API OMISScene omisNewScene(void) {
    return guarded<OMISScene>(nullptr, [&] { return new OMISSceneImpl(); });
}

OMIS_API void omisRetainScene(OMISScene scene) {
    retain_handle(scene, "scene");
}

OMIS_API void omisReleaseScene(OMISScene scene) {
    release_handle(scene, "scene");
}

OMIS_API unsigned int omisAddMesh(OMISScene scene, const void* vertices,
                                       OMISDataType type, size_t vertexByteStride,
                                       size_t numVertices, const uint32_t* triangles,
                                       size_t numTriangles, const void* cornerNormals,
                                       const void* cornerUVs, const float* emission) {
    return guarded<unsigned int>(OMIS_INVALID_ID, [&] {
        auto* s = checked(scene, "scene");
        const std::size_t scalar = scalar_size(type);
        if (numVertices > 0) checked(vertices, "vertices");
        if (numTriangles > 0) checked(triangles, "triangles");
        if (vertexByteStride != 0 && vertexByteStride < 3 * scalar)
            throw std::invalid_argument(
                "vertexByteStride: " + std::to_string(vertexByteStride) +
                " bytes is less than one vertex (" + std::to_string(3 * scalar) + ")");
        // Sizes the core would refuse anyway; checked here so no product below overflows.
        if (numVertices >= (std::size_t(1) << 32))
            throw std::invalid_argument("numVertices: too many vertices for Embree");
        if (numTriangles > (std::size_t(1) << 31))
            throw std::invalid_argument("numTriangles: too many triangles for Embree");

        std::vector<unsigned char> vertex_copy, normal_copy, uv_copy;
        static const double no_vertex = 0;
        omis::MeshInput in;
        in.positions = numVertices > 0 ? scalar_array(vertices, type, vertexByteStride,
                                                      numVertices, 3, vertex_copy)
                                       : omis::ScalarArray::of(&no_vertex, 0, 3);
        in.triangles.data = triangles;
        in.triangles.rows = numTriangles;
        in.triangles.cols = 3;
        if (cornerNormals && numTriangles > 0)
            in.normals =
                scalar_array(cornerNormals, type, 0, 3 * numTriangles, 3, normal_copy);
        if (cornerUVs && numTriangles > 0)
            in.uvs = scalar_array(cornerUVs, type, 0, 3 * numTriangles, 2, uv_copy);
        if (emission) in.emission = omis::Vec3{emission[0], emission[1], emission[2]};

        auto lock = s->lock_for_build("omisAddMesh");
        return static_cast<unsigned int>(s->scene.add_mesh(in));
    });
}

OMIS_API unsigned int omisAddRectLight(OMISScene scene, const double corner[3],
                                       const double edgeU[3], const double edgeV[3],
                                       const double radiance[3], bool twoSided,
                                       double spread) {
    return add_planar_light(scene, "omisAddRectLight", omis::make_rect_light,
                            {corner, edgeU, edgeV}, {"corner", "edgeU", "edgeV"}, radiance,
                            twoSided, spread);
}

OMIS_API unsigned int omisAddEllipseLight(OMISScene scene, const double center[3],
                                          const double axisA[3], const double axisB[3],
                                          const double radiance[3], bool twoSided,
                                          double spread) {
    return add_planar_light(scene, "omisAddEllipseLight", omis::make_ellipse_light,
                            {center, axisA, axisB}, {"center", "axisA", "axisB"}, radiance,
                            twoSided, spread);
}

OMIS_API unsigned int omisAddPointLight(OMISScene scene, const double position[3],
                                             const double intensity[3], double radius) {
    return add_light(scene, "omisAddPointLight", [&] {
        return omis::make_point_light(vec3(position, "position"),
                                      vec3(intensity, "intensity"), radius);
    });
}

OMIS_API unsigned int omisAddSpotLight(OMISScene scene, const double position[3],
                                            const double direction[3],
                                            const double intensity[3], double radius,
                                            double spotSize, double spotBlend) {
    return add_light(scene, "omisAddSpotLight", [&] {
        return omis::make_spot_light(
            vec3(position, "position"), vec3(direction, "direction"),
            vec3(intensity, "intensity"), radius, spotSize, spotBlend);
    });
}

OMIS_API unsigned int omisAddSunLight(OMISScene scene, const double direction[3],
                                           const double irradiance[3], double angle) {
    return add_light(scene, "omisAddSunLight", [&] {
        return omis::make_sun_light(vec3(direction, "direction"),
                                    vec3(irradiance, "irradiance"), angle);
    });
}

OMIS_API unsigned int omisSetWorld(OMISScene scene, const double radiance[3]) {
    return add_light(scene, "omisSetWorld",
                     [&] { return omis::make_world_light(vec3(radiance, "radiance")); });
}

namespace {

// A world image's size, checked before anything is sized from it.
void check_world_size(std::size_t width, std::size_t height) {
    if (width == 0 || height == 0 || width > (1u << 16) || height > (1u << 16))
        throw std::invalid_argument("world image: width and height must be in 1..65536, got " +
                                    std::to_string(width) + " x " + std::to_string(height));
}

// The world light of an image (rows top first), with the rotation checked.
omis::Light world_image_light(std::vector<float> rgb, std::size_t width, std::size_t height,
                              const double rotation[3], bool compensate) {
    check_world_size(width, height);
    const omis::Vec3 euler = rotation ? vec3(rotation, "rotation") : omis::Vec3();
    return omis::make_environment_light(std::make_shared<const omis::EnvironmentMap>(
        std::move(rgb), int(width), int(height), euler, compensate));
}

}  // namespace

OMIS_API unsigned int omisSetWorldImage(OMISScene scene, const float* rgb, size_t width,
                                        size_t height, size_t rowByteStride,
                                        const double rotation[3], bool compensate) {
    return add_light(scene, "omisSetWorldImage", [&] {
        if (!rgb) throw std::invalid_argument("rgb: is NULL");
        check_world_size(width, height);  // before the copy is sized from them
        const std::size_t row_floats = width * 3;
        const std::size_t stride = rowByteStride ? rowByteStride : row_floats * sizeof(float);
        if (stride < row_floats * sizeof(float) || stride % sizeof(float) != 0)
            throw std::invalid_argument("rowByteStride: must be 0 or a multiple of 4 of at "
                                        "least width x 3 x 4 bytes");
        std::vector<float> packed(row_floats * height);
        const char* bytes = reinterpret_cast<const char*>(rgb);
        for (std::size_t r = 0; r < height; ++r)
            std::memcpy(packed.data() + r * row_floats, bytes + r * stride,
                        row_floats * sizeof(float));
        return world_image_light(std::move(packed), width, height, rotation, compensate);
    });
}

OMIS_API unsigned int omisSetWorldImageFile(OMISScene scene, const char* path,
                                            const double rotation[3], bool compensate) {
    return add_light(scene, "omisSetWorldImageFile", [&] {
        if (!path) throw std::invalid_argument("path: is NULL");
        omis::RgbImage image;
        try {
            image = omis::read_rgb_image(path);
        } catch (const std::runtime_error& e) {
            throw std::invalid_argument(e.what());
        }
        return world_image_light(std::move(image.rgb), std::size_t(image.width),
                                 std::size_t(image.height), rotation, compensate);
    });
}

OMIS_API void omisSetLightFlags(OMISScene scene, unsigned int light, bool castShadow,
                                     bool visibleToBsdf) {
    guarded_void([&] {
        auto* s = checked(scene, "scene");
        auto lock = s->lock_for_build("omisSetLightFlags");
        const std::size_t n = s->scene.lights().size();
        if (light >= n)
            throw std::invalid_argument("light: no light with id " +
                                        std::to_string(light) + " (the scene has " +
                                        std::to_string(n) + ")");
        s->scene.set_light_flags(light, castShadow, visibleToBsdf);
    });
}

OMIS_API void omisSetMeshLights(OMISScene scene, bool enabled) {
    guarded_void([&] {
        auto* s = checked(scene, "scene");
        auto lock = s->lock_for_build("omisSetMeshLights");
        s->scene.set_mesh_lights(enabled);
    });
}

OMIS_API void omisSetMeshReceiver(OMISScene scene, unsigned int mesh, OMISReceiver receiver,
                                  double roughness) {
    guarded_void([&] {
        auto* s = checked(scene, "scene");
        omis::ReceiverModel model;
        const int value = enum_value(receiver);  // checked before any conversion
        switch (value) {
            case OMIS_RECEIVER_LAMBERT: model = omis::ReceiverModel::Lambert; break;
            case OMIS_RECEIVER_PRINCIPLED_DIFFUSE:
                model = omis::ReceiverModel::PrincipledDiffuse;
                break;
            case OMIS_RECEIVER_OREN_NAYAR: model = omis::ReceiverModel::OrenNayar; break;
            default:
                throw std::invalid_argument("receiver: unknown value " + std::to_string(value));
        }
        auto lock = s->lock_for_build("omisSetMeshReceiver");
        s->scene.set_mesh_receiver(mesh, omis::make_receiver(model, roughness));
    });
}

OMIS_API void omisCommitScene(OMISScene scene) {
    guarded_void([&] {
        auto* s = checked(scene, "scene");
        std::lock_guard<std::mutex> lock(s->build_mutex);
        if (s->committed.load()) return;
        s->scene.commit();
        s->committed.store(true);
    });
}

OMIS_API size_t omisGetEffectPlan(OMISScene scene, const char* techniques,
                                  const int* samples, char* buffer, size_t bufferSize) {
    return guarded<size_t>(0, [&] {
        auto* s = checked(scene, "scene");
        ScopedRetain hold(s);
        if (bufferSize > 0) checked(buffer, "buffer");
        const omis::Scene& sc = s->committed_scene("omisGetEffectPlan");
        const TechniqueChoice choice = choose_techniques(sc, techniques, samples);
        return copy_text(omis::plan_effects(sc, choice.techniques, choice.samples).to_string(),
                         buffer, bufferSize);
    });
}

OMIS_API size_t omisGetTechniqueNames(char* buffer, size_t bufferSize) {
    return guarded<size_t>(0, [&] {
        if (bufferSize > 0) checked(buffer, "buffer");
        std::string text;
        for (const std::string& name : omis::technique_names())
            text += (text.empty() ? "" : ",") + name;
        return copy_text(text, buffer, bufferSize);
    });
}
