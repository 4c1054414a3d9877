// C ABI of scene snapshots and mesh names (omis.h, "Scene snapshots").
#include <memory>
#include <string>

#include "api_common.h"
#include "io/scene_snapshot.h"
#include "scene_impl.h"

using namespace omis::api;

namespace {

// A snapshot's faults are the caller's input: invalid argument, with the
// reader's message (which names the part of the file).
template <class Body>
void as_argument_error(Body&& body) {
    try {
        body();
    } catch (const omis::SnapshotError& e) {
        throw ApiError(OMIS_ERROR_INVALID_ARGUMENT, e.what());
    }
}

OMISScene loaded_scene(const std::function<void(omis::Scene&)>& load) {
    auto scene = std::make_unique<OMISSceneImpl>();
    as_argument_error([&] { load(scene->scene); });
    scene->committed.store(true);
    return scene.release();
}

}  // namespace

OMIS_API bool omisSaveScene(OMISScene scene, const char* path) {
    return guarded(false, [&] {
        auto* s = checked(scene, "scene");
        const std::string file = checked(path, "path");
        ScopedRetain hold(s);
        std::lock_guard<std::mutex> lock(s->build_mutex);
        omis::save_snapshot(s->scene, file);
        return true;
    });
}

OMIS_API size_t omisSaveSceneToMemory(OMISScene scene, void* buffer, size_t bufferSize) {
    return guarded<size_t>(0, [&] {
        auto* s = checked(scene, "scene");
        ScopedRetain hold(s);
        std::vector<unsigned char> bytes;
        {
            std::lock_guard<std::mutex> lock(s->build_mutex);
            bytes = omis::save_snapshot(s->scene);
        }
        if (buffer && bufferSize >= bytes.size()) std::memcpy(buffer, bytes.data(), bytes.size());
        return bytes.size();
    });
}

OMIS_API OMISScene omisLoadScene(const char* path) {
    return guarded<OMISScene>(nullptr, [&] {
        const std::string file = checked(path, "path");
        return loaded_scene([&](omis::Scene& s) { omis::load_snapshot(file, s); });
    });
}

OMIS_API OMISScene omisLoadSceneFromMemory(const void* data, size_t size) {
    return guarded<OMISScene>(nullptr, [&] {
        if (size > 0) checked(data, "data");
        const auto* bytes = static_cast<const unsigned char*>(data);
        return loaded_scene([&](omis::Scene& s) { omis::load_snapshot(bytes, size, s); });
    });
}

OMIS_API void omisSetMeshName(OMISScene scene, unsigned int mesh, const char* name) {
    guarded_void([&] {
        auto* s = checked(scene, "scene");
        const std::string text = checked(name, "name");
        std::lock_guard<std::mutex> lock(s->build_mutex);
        s->scene.set_mesh_name(mesh, text);
    });
}

OMIS_API unsigned int omisFindMesh(OMISScene scene, const char* name) {
    return guarded<unsigned int>(OMIS_INVALID_ID, [&] {
        auto* s = checked(scene, "scene");
        const std::string text = checked(name, "name");
        std::lock_guard<std::mutex> lock(s->build_mutex);
        const auto& meshes = s->scene.geometry().meshes();
        for (std::size_t m = 0; m < meshes.size(); ++m)
            if (meshes[m].name == text) return static_cast<unsigned int>(m);
        throw std::invalid_argument("name: no mesh is named '" + text + "'");
    });
}

OMIS_API size_t omisGetMeshName(OMISScene scene, unsigned int mesh, char* buffer,
                                size_t bufferSize) {
    return guarded<size_t>(0, [&] {
        auto* s = checked(scene, "scene");
        std::lock_guard<std::mutex> lock(s->build_mutex);
        if (mesh >= s->scene.geometry().num_meshes())
            throw std::invalid_argument("mesh: id " + std::to_string(mesh) + " is out of range");
        return copy_text(s->scene.geometry().mesh(mesh).name, buffer, bufferSize);
    });
}

OMIS_API unsigned int omisGetMeshCount(OMISScene scene) {
    return guarded<unsigned int>(OMIS_INVALID_ID, [&] {
        auto* s = checked(scene, "scene");
        std::lock_guard<std::mutex> lock(s->build_mutex);
        return static_cast<unsigned int>(s->scene.geometry().num_meshes());
    });
}
