// Scene snapshots and mesh names on omis.Scene (Scene.save, Scene.load, ...),
// and the native pieces of a distributed lightmap bake (omis.farm).
#include "scene.h"

namespace omis_py {
namespace {

void save(const Scene& scene, const std::string& path) {
    bool ok;
    {
        py::gil_scoped_release release;
        ok = omisSaveScene(scene.get(), c_string(path, "path"));
    }
    if (!ok) raise_pending_error();
}

py::bytes to_bytes(const Scene& scene) {
    const size_t n = omisSaveSceneToMemory(scene.get(), nullptr, 0);
    if (n == 0) raise_pending_error();
    std::string bytes(n, '\0');
    if (omisSaveSceneToMemory(scene.get(), &bytes[0], n) != n) raise_pending_error();
    return py::bytes(bytes);
}

Scene load(const std::string& path) {
    OMISScene handle;
    {
        py::gil_scoped_release release;
        handle = omisLoadScene(c_string(path, "path"));
    }
    return Scene::adopt(handle);
}

Scene from_bytes(const py::bytes& data) {
    const std::string_view view = data;  // no copy; the bytes object outlives the call
    OMISScene handle;
    {
        py::gil_scoped_release release;
        handle = omisLoadSceneFromMemory(view.data(), view.size());
    }
    return Scene::adopt(handle);
}

void set_mesh_name(const Scene& scene, long long mesh, const std::string& name) {
    if (mesh < 0 || mesh >= (long long)OMIS_INVALID_ID)
        bad("mesh", "no mesh with id " + std::to_string(mesh));
    omisGetError(nullptr);
    omisSetMeshName(scene.get(), (unsigned int)mesh, c_string(name, "name"));
    raise_if_pending();
}

unsigned int find_mesh(const Scene& scene, const std::string& name) {
    const unsigned int id = omisFindMesh(scene.get(), c_string(name, "name"));
    if (id == OMIS_INVALID_ID) raise_pending_error();
    return id;
}

std::string mesh_name(const Scene& scene, long long mesh) {
    if (mesh < 0 || mesh >= (long long)OMIS_INVALID_ID)
        bad("mesh", "no mesh with id " + std::to_string(mesh));
    omisGetError(nullptr);
    const size_t n = omisGetMeshName(scene.get(), (unsigned int)mesh, nullptr, 0);
    raise_if_pending();
    std::string name(n + 1, '\0');
    omisGetMeshName(scene.get(), (unsigned int)mesh, &name[0], name.size());
    name.resize(n);
    return name;
}

unsigned int num_meshes(const Scene& scene) {
    const unsigned int n = omisGetMeshCount(scene.get());
    if (n == OMIS_INVALID_ID) raise_pending_error();
    return n;
}

}  // namespace

void init_snapshot(py::module_& m) {
    auto scene = py::reinterpret_borrow<py::class_<Scene>>(m.attr("Scene"));
    scene.def("save", &save, py::arg("path"),
              "Writes a snapshot of everything a bake reads (meshes, names, UVs, normals, "
              "receivers, lights, world, options) to path, atomically. Before or after commit.")
        .def("to_bytes", &to_bytes, "The snapshot as bytes (Scene.from_bytes reads it).")
        .def_static("load", &load, py::arg("path"),
                    "A committed Scene from a snapshot file: it bakes the same bits as the "
                    "scene saved. Truncated, corrupted or other-version files raise ValueError.")
        .def_static("from_bytes", &from_bytes, py::arg("data"),
                    "A committed Scene from snapshot bytes (Scene.to_bytes).")
        .def("set_mesh_name", &set_mesh_name, py::arg("mesh"), py::arg("name"),
             "Names a mesh (kept in snapshots; the command line's --mesh takes names).")
        .def("find_mesh", &find_mesh, py::arg("name"),
             "The id of the first mesh of that name (ValueError when none is).")
        .def("mesh_name", &mesh_name, py::arg("mesh"), "A mesh's name ('' when unnamed).")
        .def_property_readonly("num_meshes", &num_meshes, "How many meshes the scene holds.");
}

}  // namespace omis_py
