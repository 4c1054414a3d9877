// pybind11 module omis._omis, built on the C ABI only (plugin/include/omis):
// this file registers the parts — estimator.cpp (combine), lighting.cpp (Scene,
// direct_lighting), bake.cpp (bake_uv, bake_vertices, BakeResult), snapshot.cpp (Scene.save,
// Scene.load, mesh names).
#include "common.h"

namespace omis_py {
void init_estimator(py::module_& m);
void init_scene(py::module_& m);
void init_bake(py::module_& m);
void init_snapshot(py::module_& m);
}  // namespace omis_py

using namespace omis_py;

PYBIND11_MODULE(_omis, m) {
    m.doc() = "omis native module (pybind11 over the omis C ABI)";
    m.attr("__version__") = OMIS_VERSION_STRING;
    if (omisGetVersion() != OMIS_VERSION)
        throw std::runtime_error("omis: the loaded libomis does not match this module's version");
    m.attr("STRATEGIES") = py::make_tuple("balance", "power", "maximum", "cutoff",
                                          "optimal-direct", "optimal-progressive");
    {  // Technique names from the library itself (one owner: core/render/techniques).
        std::string names(omisGetTechniqueNames(nullptr, 0), '\0');
        omisGetTechniqueNames(names.data(), names.size() + 1);
        py::list techniques;
        for (std::size_t begin = 0; begin <= names.size();) {
            const std::size_t end = std::min(names.find(',', begin), names.size());
            techniques.append(names.substr(begin, end - begin));
            begin = end + 1;
        }
        m.attr("TECHNIQUES") = py::tuple(techniques);
    }
    g_cancelled = PyErr_NewExceptionWithDoc(
        "omis.Cancelled", "A long call stopped because its progress callable returned False.",
        PyExc_RuntimeError, nullptr);
    if (!g_cancelled) throw py::error_already_set();
    m.add_object("Cancelled", py::handle(g_cancelled));  // the module keeps it alive

    init_estimator(m);
    init_scene(m);
    init_bake(m);
    init_snapshot(m);
}
