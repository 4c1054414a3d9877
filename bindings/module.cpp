// pybind11 module omis._omis, built on the C ABI only (plugin/include/omis).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <algorithm>
#include <functional>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "omis/omis.hpp"

namespace py = pybind11;

namespace {

// omis.Cancelled, created at import.
PyObject* g_cancelled = nullptr;

[[noreturn]] void raise_cancelled(const std::string& message) {
    PyErr_SetString(g_cancelled, message.c_str());
    throw py::error_already_set();
}

// Turns a C error into the Python exception users expect.
[[noreturn]] void raise_error(OMISError code, const std::string& message) {
    if (code == OMIS_ERROR_INVALID_ARGUMENT) throw py::value_error(message);
    if (code == OMIS_ERROR_CANCELLED) raise_cancelled(message);
    if (code == OMIS_ERROR_NONE)
        throw std::runtime_error("omis: call failed without an error message");
    throw std::runtime_error(message);
}

// Turns the thread's pending C error into a Python exception.
[[noreturn]] void raise_pending_error() {
    const char* message = nullptr;
    const OMISError code = omisGetError(&message);
    raise_error(code, message ? message : "omis error");
}

// After a void call: raises the error it left, if any.
void raise_if_pending() {
    const char* message = nullptr;
    const OMISError code = omisGetError(&message);
    if (code != OMIS_ERROR_NONE) raise_error(code, message ? message : "omis error");
}

[[noreturn]] void bad(const std::string& argument, const std::string& problem) {
    throw py::value_error(argument + ": " + problem);
}

std::string type_name(const py::handle& obj) {
    return py::str(py::type::handle_of(obj).attr("__name__"));
}

// Keyword values checked here, so a wrong type names the argument instead of
// pybind11's "Unable to cast Python instance to C++ type".
bool bool_arg(const py::handle& obj, const char* name) {
    if (py::isinstance<py::bool_>(obj)) return obj.cast<bool>();
    if (type_name(obj) == "bool_") return py::bool_(py::reinterpret_borrow<py::object>(obj));
    throw py::type_error(std::string(name) + ": expected True or False, got " + type_name(obj));
}

double number_arg(const py::handle& obj, const char* name) {
    if (py::isinstance<py::bool_>(obj) || !PyNumber_Check(obj.ptr()) ||
        PyComplex_Check(obj.ptr()) || py::isinstance<py::array>(obj))
        throw py::type_error(std::string(name) + ": expected a real number, got " +
                             type_name(obj));
    const double v = PyFloat_AsDouble(obj.ptr());
    if (PyErr_Occurred()) {
        PyErr_Clear();
        throw py::type_error(std::string(name) + ": expected a real number, got " +
                             type_name(obj));
    }
    return v;
}

// A string for the C ABI, which would stop at an embedded NUL ('a\0.exr' → 'a').
const char* c_string(const std::string& text, const char* name) {
    if (text.find('\0') != std::string::npos) bad(name, "contains a NUL byte");
    return text.c_str();
}

std::string shape_of(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i)
        s += (i ? ", " : "") + std::to_string(a.shape(i));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

// A C-contiguous float64 view of a floating-point array; other dtypes are refused.
py::array_t<double, py::array::c_style | py::array::forcecast> as_float_array(const py::handle& obj,
                                                       const char* name) {
    py::array a = py::array::ensure(obj);
    if (!a) bad(name, "expected a numpy array");
    const char kind = a.dtype().kind();
    if (kind != 'f') bad(name, "expected a floating-point array, got dtype " +
                                   std::string(py::str(a.dtype())));
    // Casting float32 (or float16) up to double is exact.
    auto out = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
    if (!out) bad(name, "could not be read as a float64 array");
    return out;
}

py::array_t<int, py::array::c_style | py::array::forcecast> as_int_array(const py::handle& obj, const char* name) {
    py::array a = py::array::ensure(obj);
    if (!a) bad(name, "expected a numpy array");
    const char kind = a.dtype().kind();
    if (kind != 'i' && kind != 'u')
        bad(name, "expected an integer array, got dtype " + std::string(py::str(a.dtype())));
    // Range-check before narrowing to C int.
    auto wide = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(a);
    if (!wide) bad(name, "could not be read as an integer array");
    for (py::ssize_t i = 0; i < wide.size(); ++i) {
        const long long v = wide.data()[i];
        if (v < -(1LL << 31) || v >= (1LL << 31))
            bad(name, "entry " + std::to_string(i) + " does not fit a 32-bit integer");
    }
    return py::array_t<int, py::array::c_style | py::array::forcecast>::ensure(wide);
}

py::object combine(const py::handle& f_in, const py::handle& pdfs_in,
                   const py::handle& technique_in, const py::handle& counts_in,
                   const std::string& strategy_name, const py::kwargs& options) {
    OMISStrategy strategy;
    if (!omisParseStrategy(c_string(strategy_name, "strategy"), &strategy))
        bad("strategy", "unknown strategy '" + strategy_name +
                            "' (balance, power, maximum, cutoff, optimal-direct, "
                            "optimal-progressive)");
    bool return_variance = false;
    std::vector<std::pair<std::string, double>> float_options;
    for (const auto& item : options) {
        const std::string key = py::str(item.first);
        if (key == "return_variance")
            return_variance = bool_arg(item.second, "return_variance");
        else if (key == "beta" || key == "cutoff")
            float_options.emplace_back(key, number_arg(item.second, key.c_str()));
        else
            throw py::type_error("combine() got an unexpected keyword argument '" + key + "'");
    }

    auto f = as_float_array(f_in, "f");
    auto pdfs = as_float_array(pdfs_in, "pdfs");
    auto technique = as_int_array(technique_in, "technique");
    auto counts = as_int_array(counts_in, "counts");

    if (f.ndim() != 1 && f.ndim() != 2) bad("f", "expected shape (S,) or (S, C), got " + shape_of(f));
    const py::ssize_t S = f.shape(0);
    const int C = f.ndim() == 2 ? int(f.shape(1)) : 1;
    if (C < 1 || C > 4) bad("f", "expected 1 to 4 channels, got " + std::to_string(C));
    if (S == 0) bad("f", "no samples");
    if (pdfs.ndim() != 2 || pdfs.shape(0) != S)
        bad("pdfs", "expected shape (" + std::to_string(S) + ", N), got " + shape_of(pdfs));
    const int N = int(pdfs.shape(1));
    if (N < 1 || N > 32) bad("pdfs", "expected 1 to 32 techniques, got " + std::to_string(N));
    if (technique.ndim() != 1 || technique.shape(0) != S)
        bad("technique", "expected shape (" + std::to_string(S) + ",), got " + shape_of(technique));
    if (counts.ndim() != 1 || counts.shape(0) != N)
        bad("counts", "expected shape (" + std::to_string(N) + ",) to match pdfs, got " +
                          shape_of(counts));

    for (py::ssize_t i = 0; i < f.size(); ++i)
        if (!std::isfinite(f.data()[i])) bad("f", "contains NaN or Inf (flat index " + std::to_string(i) + ")");
    for (py::ssize_t i = 0; i < pdfs.size(); ++i) {
        const double p = pdfs.data()[i];
        if (!std::isfinite(p)) bad("pdfs", "contains NaN or Inf at sample " + std::to_string(i / N));
        if (p < 0) bad("pdfs", "negative density at sample " + std::to_string(i / N));
    }
    long long per_round = 0;
    for (int k = 0; k < N; ++k) {
        if (counts.data()[k] < 0) bad("counts", "entry " + std::to_string(k) + " is negative");
        per_round += counts.data()[k];
    }
    if (per_round == 0) bad("counts", "all zero: no technique is sampled");
    if (S % per_round != 0)
        bad("counts", "S = " + std::to_string(S) + " samples is not a whole number of rounds of " +
                          std::to_string(per_round) + " (sum of counts)");
    for (py::ssize_t s = 0; s < S; ++s) {
        const int t = technique.data()[s];
        if (t < 0 || t >= N)
            bad("technique", "sample " + std::to_string(s) + " names technique " +
                                 std::to_string(t) + ", outside [0, " + std::to_string(N) + ")");
        if (!(pdfs.data()[s * N + t] > 0))
            bad("pdfs", "sample " + std::to_string(s) + " has zero density under its own technique " +
                            std::to_string(t));
    }

    omis::capi::EstimatorRef estimator(omisNewEstimator(strategy, N, C, counts.data()));
    if (!estimator) raise_pending_error();
    for (const auto& [key, value] : float_options) {
        omisSetEstimatorFloat(estimator.get(), key.c_str(), value);
    }
    omisCommitEstimator(estimator.get());
    {
        const char* message = nullptr;
        if (omisGetError(&message) != OMIS_ERROR_NONE)
            bad(float_options.empty() ? "options" : float_options.front().first,
                message ? message : "invalid option");
    }

    py::array_t<double> estimate(C), variance(C);
    bool ok;
    {
        py::gil_scoped_release release;
        ok = omisEstimatorAddSamples(estimator.get(), size_t(S), technique.data(), sizeof(int),
                                     pdfs.data(), sizeof(double) * N, f.data(),
                                     sizeof(double) * C) &&
             omisEstimatorGetResult(estimator.get(), estimate.mutable_data(),
                                    variance.mutable_data());
    }
    if (!ok) raise_pending_error();
    if (return_variance) return py::make_tuple(estimate, variance);
    return std::move(estimate);
}

// ---- Scenes and direct lighting ---------------------------------------------

using Triple = std::array<double, 3>;

// Any sequence of 3 real numbers; with `grey`, a single number means (v, v, v).
Triple triple(const py::handle& obj, const char* name, bool grey = false) {
    const std::string expected = grey ? "expected 3 numbers (RGB) or one number (grey)"
                                      : "expected a sequence of 3 numbers";
    if (obj.is_none() || py::isinstance<py::str>(obj) || py::isinstance<py::bytes>(obj))
        bad(name, expected + ", got " + Py_TYPE(obj.ptr())->tp_name);
    py::array a = py::array::ensure(obj);
    if (!a) bad(name, expected);
    const char kind = a.dtype().kind();
    if (kind != 'f' && kind != 'i' && kind != 'u')
        bad(name, expected + ", got dtype " + std::string(py::str(a.dtype())));
    if (!(a.ndim() == 1 && a.shape(0) == 3) && !(grey && a.ndim() == 0))
        bad(name, expected + ", got shape " + shape_of(a));
    auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
    Triple t;
    for (int k = 0; k < 3; ++k) t[k] = d.data()[a.ndim() == 0 ? 0 : k];
    for (double v : t)
        if (!std::isfinite(v)) bad(name, "contains NaN or Inf");
    return t;
}

double finite(double v, const char* name) {
    if (!std::isfinite(v)) bad(name, "must be finite");
    return v;
}

// A light id, or the pending error.
unsigned int checked_id(unsigned int id) {
    if (id == OMIS_INVALID_ID) raise_pending_error();
    return id;
}

void check_rows_finite(const py::array& a, const char* name) {
    const py::ssize_t cols = a.shape(1);
    auto check = [&](const auto* data) {
        for (py::ssize_t i = 0; i < a.size(); ++i)
            if (!std::isfinite(double(data[i])))
                bad(name, "row " + std::to_string(i / cols) + " is not finite");
    };
    if (a.itemsize() == 4)
        check(static_cast<const float*>(a.data()));
    else
        check(static_cast<const double*>(a.data()));
}

// A float32/float64 (rows, cols) array; rows = -1 accepts any row count.
py::array float_rows(const py::handle& obj, const char* name, py::ssize_t rows, py::ssize_t cols,
                     const std::string& shape_text) {
    py::array a = py::array::ensure(obj);
    if (!a) bad(name, "expected a numpy array");
    if (a.dtype().kind() != 'f' || (a.itemsize() != 4 && a.itemsize() != 8))
        bad(name, "expected a float32 or float64 array, got dtype " + std::string(py::str(a.dtype())));
    if (a.ndim() != 2 || a.shape(1) != cols || (rows >= 0 && a.shape(0) != rows))
        bad(name, "expected shape " + shape_text + ", got " + shape_of(a));
    return a;
}

template <class T>
py::array packed(const py::array& a) {
    return py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(a);
}

class Scene {
public:
    Scene() : ref_(omisNewScene()) {
        if (!ref_) raise_pending_error();
    }
    OMISScene get() const { return ref_.get(); }

    unsigned int add_mesh(const py::handle& vertices_in, const py::handle& triangles_in,
                          const py::handle& normals_in, const py::handle& uvs_in,
                          const py::handle& emission_in) {
        py::array vertices = float_rows(vertices_in, "vertices", -1, 3, "(V, 3)");
        const py::ssize_t V = vertices.shape(0);
        if (V == 0) bad("vertices", "no vertices");

        py::array tri = py::array::ensure(triangles_in);
        if (!tri) bad("triangles", "expected a numpy array");
        const char kind = tri.dtype().kind();
        if (kind != 'i' && kind != 'u')
            bad("triangles", "expected an integer array, got dtype " + std::string(py::str(tri.dtype())));
        if (tri.ndim() != 2 || tri.shape(1) != 3)
            bad("triangles", "expected shape (T, 3), got " + shape_of(tri));
        const py::ssize_t T = tri.shape(0);
        if (T == 0) bad("triangles", "no triangles");
        auto wide = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(tri);
        if (!wide) bad("triangles", "could not be read as an integer array");
        std::vector<std::uint32_t> indices(size_t(3 * T));
        for (py::ssize_t i = 0; i < 3 * T; ++i) {
            const long long v = wide.data()[i];
            if (v < 0 || v >= V)
                bad("triangles", "triangle " + std::to_string(i / 3) + " has vertex index " +
                                     std::to_string(v) + ", outside [0, " + std::to_string(V) + ")");
            indices[size_t(i)] = std::uint32_t(v);
        }

        const std::string corners = "(3T, %) = (" + std::to_string(3 * T) + ", %)";
        auto corner_shape = [&](const char* cols) {
            std::string s = corners;
            for (auto pos = s.find('%'); pos != std::string::npos; pos = s.find('%'))
                s.replace(pos, 1, cols);
            return s;
        };
        const bool has_normals = !normals_in.is_none(), has_uvs = !uvs_in.is_none();
        py::array normals, uvs;  // empty unless given
        if (has_normals)
            normals = float_rows(normals_in, "normals", 3 * T, 3, corner_shape("3"));
        if (has_uvs) uvs = float_rows(uvs_in, "uvs", 3 * T, 2, corner_shape("2"));

        // One scalar type for all: float32 if every array is, else float64.
        bool f32 = vertices.itemsize() == 4;
        if (has_normals) f32 = f32 && normals.itemsize() == 4;
        if (has_uvs) f32 = f32 && uvs.itemsize() == 4;
        const py::ssize_t item = f32 ? 4 : 8;
        auto to_type = [&](const py::array& a) { return f32 ? packed<float>(a) : packed<double>(a); };

        // Rows of 3 scalars at any positive row stride go to the ABI as they are.
        const bool strided_ok = vertices.itemsize() == item && vertices.strides(1) == item &&
                                vertices.strides(0) >= 3 * item && vertices.strides(0) % item == 0;
        size_t vertex_stride = strided_ok ? size_t(vertices.strides(0)) : 0;
        if (!strided_ok) vertices = to_type(vertices);
        if (has_normals) normals = to_type(normals);
        if (has_uvs) uvs = to_type(uvs);

        // Finite checks (strided vertices checked row by row).
        for (py::ssize_t i = 0; i < V; ++i) {
            const auto* row = static_cast<const char*>(vertices.data()) +
                              i * (vertex_stride ? py::ssize_t(vertex_stride) : 3 * item);
            for (int k = 0; k < 3; ++k) {
                const double v = f32 ? double(reinterpret_cast<const float*>(row)[k])
                                     : reinterpret_cast<const double*>(row)[k];
                if (!std::isfinite(v)) bad("vertices", "row " + std::to_string(i) + " is not finite");
            }
        }
        if (has_normals) check_rows_finite(normals, "normals");
        if (has_uvs) check_rows_finite(uvs, "uvs");

        float emission[3];
        const bool emissive = !emission_in.is_none();
        if (emissive) {
            const Triple e = triple(emission_in, "emission", true);
            for (int k = 0; k < 3; ++k) {
                if (e[k] < 0) bad("emission", "must not be negative");
                emission[k] = float(e[k]);
            }
        }

        unsigned int id;
        {
            py::gil_scoped_release release;
            id = omisSceneAddMesh(get(), vertices.data(), f32 ? OMIS_DATA_FLOAT32 : OMIS_DATA_FLOAT64,
                                  vertex_stride, size_t(V), indices.data(), size_t(T),
                                  has_normals ? normals.data() : nullptr,
                                  has_uvs ? uvs.data() : nullptr,
                                  emissive ? emission : nullptr);
        }
        return checked_id(id);
    }

    unsigned int add_rect_light(const py::handle& corner, const py::handle& edge_u,
                                const py::handle& edge_v, const py::handle& radiance,
                                bool two_sided, double spread) {
        const Triple c = triple(corner, "corner"), u = triple(edge_u, "edge_u"),
                     v = triple(edge_v, "edge_v"), L = triple(radiance, "radiance", true);
        if (cross_length(u, v) == 0) bad("edge_u", "edge_u and edge_v span zero area");
        return checked_id(omisSceneAddRectLight(get(), c.data(), u.data(), v.data(), L.data(),
                                                two_sided, finite(spread, "spread")));
    }

    unsigned int add_ellipse_light(const py::handle& center, const py::handle& axis_u,
                                   const py::handle& axis_v, const py::handle& radiance,
                                   bool two_sided, double spread) {
        const Triple c = triple(center, "center"), u = triple(axis_u, "axis_u"),
                     v = triple(axis_v, "axis_v"), L = triple(radiance, "radiance", true);
        if (cross_length(u, v) == 0) bad("axis_u", "axis_u and axis_v span zero area");
        return checked_id(omisSceneAddEllipseLight(get(), c.data(), u.data(), v.data(), L.data(),
                                                   two_sided, finite(spread, "spread")));
    }

    unsigned int add_disk_light(const py::handle& center, const py::handle& normal, double radius,
                                const py::handle& radiance, bool two_sided, double spread) {
        const Triple c = triple(center, "center"), L = triple(radiance, "radiance", true);
        Triple n = triple(normal, "normal");
        // Scaled by the largest component first: huge or tiny normals are fine.
        const double largest = std::max({std::abs(n[0]), std::abs(n[1]), std::abs(n[2])});
        if (!(largest > 0) || !std::isfinite(largest))
            bad("normal", "must have a finite, non-zero length");
        for (double& x : n) x /= largest;
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (double& x : n) x /= len;
        if (!(radius > 0) || !std::isfinite(radius)) bad("radius", "must be positive and finite");
        // Semi-axes s, t with s × t = n (Duff et al. 2017): the disk emits along n.
        const double sign = std::copysign(1.0, n[2]);
        const double a = -1.0 / (sign + n[2]), b = n[0] * n[1] * a;
        const Triple s{radius * (1 + sign * n[0] * n[0] * a), radius * sign * b, -radius * sign * n[0]};
        const Triple t{radius * b, radius * (sign + n[1] * n[1] * a), -radius * n[1]};
        const unsigned int id = omisSceneAddEllipseLight(get(), c.data(), s.data(), t.data(),
                                                         L.data(), two_sided,
                                                         finite(spread, "spread"));
        if (id == OMIS_INVALID_ID) {
            // The core judges the semi-axes this function made from `radius`.
            const char* message = nullptr;
            const OMISError code = omisGetError(&message);
            std::string text = message ? message : "disk light: error";
            const std::string axes = "axis_u, axis_v: ";
            const std::string r = "radius: " + std::string(py::repr(py::float_(radius))) + " m";
            const std::size_t verdict = text.find("is too");
            if (text.rfind(axes, 0) == 0 && verdict != std::string::npos)
                text = r + " " + text.substr(verdict);
            else if (text.rfind("axis_", 0) == 0)
                text = r + text.substr(text.find(':'));
            raise_error(code, text);
        }
        return id;
    }

    unsigned int add_point_light(const py::handle& position, const py::handle& intensity,
                                 double radius) {
        const Triple p = triple(position, "position"), I = triple(intensity, "intensity", true);
        return checked_id(omisSceneAddPointLight(get(), p.data(), I.data(), finite(radius, "radius")));
    }

    unsigned int add_spot_light(const py::handle& position, const py::handle& direction,
                                const py::handle& intensity, double spot_size, double spot_blend,
                                double radius) {
        const Triple p = triple(position, "position"), d = triple(direction, "direction"),
                     I = triple(intensity, "intensity", true);
        return checked_id(omisSceneAddSpotLight(get(), p.data(), d.data(), I.data(),
                                                finite(radius, "radius"),
                                                finite(spot_size, "spot_size"),
                                                finite(spot_blend, "spot_blend")));
    }

    unsigned int add_sun_light(const py::handle& direction, const py::handle& irradiance,
                               double angle) {
        const Triple d = triple(direction, "direction"), E = triple(irradiance, "irradiance", true);
        return checked_id(omisSceneAddSunLight(get(), d.data(), E.data(), finite(angle, "angle")));
    }

    unsigned int set_world(const py::handle& radiance) {
        const Triple L = triple(radiance, "radiance", true);
        return checked_id(omisSceneSetWorld(get(), L.data()));
    }

    void set_light_flags(long long light, bool cast_shadow, bool visible_to_bsdf) {
        if (light < 0 || light >= (long long)OMIS_INVALID_ID)
            bad("light", "no light with id " + std::to_string(light));
        omisGetError(nullptr);  // void call: start from a clean error state
        omisSceneSetLightFlags(get(), (unsigned int)light, cast_shadow, visible_to_bsdf);
        raise_if_pending();
    }

    // "lambert", "principled" (Principled BSDF's diffuse) or "oren-nayar"
    // (Diffuse BSDF): the closure a mesh has when baked (render/receiver.h).
    void set_receiver(long long mesh, const std::string& model, double roughness) {
        if (mesh < 0 || mesh >= (long long)OMIS_INVALID_ID)
            bad("mesh", "no mesh with id " + std::to_string(mesh));
        OMISReceiver receiver = OMIS_RECEIVER_LAMBERT;
        if (model == "lambert") receiver = OMIS_RECEIVER_LAMBERT;
        else if (model == "principled") receiver = OMIS_RECEIVER_PRINCIPLED_DIFFUSE;
        else if (model == "oren-nayar") receiver = OMIS_RECEIVER_OREN_NAYAR;
        else
            bad("model", "unknown receiver '" + model +
                             "' (lambert, principled or oren-nayar)");
        omisGetError(nullptr);  // void call: start from a clean error state
        omisSetMeshReceiver(get(), (unsigned int)mesh, receiver, roughness);
        raise_if_pending();
    }

    void commit() {
        omisGetError(nullptr);
        {
            py::gil_scoped_release release;
            omisCommitScene(get());
        }
        raise_if_pending();
    }

private:
    static double cross_length(const Triple& u, const Triple& v) {
        const double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2],
                     z = u[0] * v[1] - u[1] * v[0];
        return std::sqrt(x * x + y * y + z * z);
    }

    omis::capi::SceneRef ref_;
};

// The technique list as the ABI wants it: comma-joined names and their counts.
struct TechniqueArgs {
    std::string names;         // empty: the effect plan's default
    std::vector<int> samples;  // one per name
    const int* samples_ptr() const { return samples.empty() ? nullptr : samples.data(); }
};

TechniqueArgs technique_args(const py::handle& techniques, const py::handle& samples) {
    TechniqueArgs out;
    if (techniques.is_none()) {
        if (!samples.is_none())
            bad("samples", "given without techniques (techniques=None lets the effect plan "
                           "choose techniques and samples)");
        return out;
    }
    std::vector<std::string> names;
    auto add = [&](std::string name, const std::string& where) {
        const auto first = name.find_first_not_of(" \t");
        name = first == std::string::npos
                   ? std::string()
                   : name.substr(first, name.find_last_not_of(" \t") - first + 1);
        if (name.empty()) bad("techniques", "empty name " + where);
        names.push_back(name);
    };
    if (py::isinstance<py::str>(techniques)) {
        const std::string list = techniques.cast<std::string>();
        std::size_t begin = 0;
        while (true) {
            const std::size_t end = std::min(list.find(',', begin), list.size());
            add(list.substr(begin, end - begin), "in '" + list + "'");
            if (end == list.size()) break;
            begin = end + 1;
        }
    } else {
        if (!py::isinstance<py::iterable>(techniques))
            bad("techniques", "expected a list of technique names");
        std::size_t i = 0;
        for (const py::handle& item : techniques) {
            if (!py::isinstance<py::str>(item))
                bad("techniques", "entry " + std::to_string(i) + " is not a string");
            const std::string name = item.cast<std::string>();
            if (name.find(',') != std::string::npos)
                bad("techniques", "entry " + std::to_string(i) + " '" + name + "' contains a comma");
            add(name, "at entry " + std::to_string(i));
            ++i;
        }
        if (names.empty()) bad("techniques", "empty list (None lets the effect plan choose)");
    }
    if (samples.is_none())
        bad("samples", "required when techniques are given: one count per technique per round");
    auto counts = as_int_array(samples, "samples");
    if (counts.ndim() != 1 || size_t(counts.shape(0)) != names.size())
        bad("samples", "expected one count per technique (" + std::to_string(names.size()) +
                           "), got shape " + shape_of(counts));
    for (std::size_t k = 0; k < names.size(); ++k) {
        out.names += (k ? "," : "") + names[k];
        out.samples.push_back(counts.data()[k]);
    }
    return out;
}

std::string plan_text(const Scene& scene, const TechniqueArgs& t) {
    const size_t n = omisGetEffectPlan(scene.get(), t.names.c_str(), t.samples_ptr(), nullptr, 0);
    if (n == 0) raise_pending_error();
    std::string text(n + 1, '\0');
    omisGetEffectPlan(scene.get(), t.names.c_str(), t.samples_ptr(), &text[0], text.size());
    text.resize(n);
    return text;
}

std::string effect_plan(const Scene& scene, const py::handle& techniques, const py::handle& samples) {
    return plan_text(scene, technique_args(techniques, samples));
}

// State shared by the calling thread and the worker running the native call.
struct NativeRun {
    std::mutex mutex;
    std::condition_variable done_cv;
    bool done = false;
    std::atomic<double> fraction{0.0};
    std::atomic<bool> cancel{false};
    bool ok = false;
    OMISError code = OMIS_ERROR_NONE;
    std::string message;
};

// OMISProgressFunction: any thread; records the furthest fraction, answers the cancel flag.
bool on_progress(void* user, double fraction) {
    auto* run = static_cast<NativeRun*>(user);
    double seen = run->fraction.load();
    while (fraction > seen && !run->fraction.compare_exchange_weak(seen, fraction)) {
    }
    return !run->cancel.load();
}

// Runs a native call on a worker thread while this thread, holding the GIL
// only when awake, wakes every 50 ms to report progress and notice Ctrl-C;
// either may set the cancel flag the native progress function answers.
// Raises KeyboardInterrupt, what progress raised, omis.Cancelled, or the
// native error; on success calls progress(1.0).
void run_interruptible(const char* what, const py::object& progress,
                       const std::function<bool(NativeRun&)>& call) {
    NativeRun run;
    std::thread worker([&] {
        run.ok = call(run);
        if (!run.ok) {
            const char* message = nullptr;
            run.code = omisGetError(&message);  // errors are per thread: read them here
            run.message = message ? message : "";
        }
        std::lock_guard<std::mutex> lock(run.mutex);
        run.done = true;
        run.done_cv.notify_all();
    });
    std::exception_ptr interruption;  // KeyboardInterrupt, or what progress raised
    bool stopped_by_callback = false;
    while (true) {
        bool done;
        {
            py::gil_scoped_release release;
            std::unique_lock<std::mutex> lock(run.mutex);
            done = run.done_cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return run.done; });
        }
        if (done) break;
        if (run.cancel.load()) continue;  // already stopping: wait for the worker
        try {
            if (PyErr_CheckSignals() != 0) throw py::error_already_set();
            if (!progress.is_none()) {
                const py::object answer = progress(run.fraction.load());
                if (!answer.is_none()) {
                    const int truth = PyObject_IsTrue(answer.ptr());
                    if (truth < 0) throw py::error_already_set();
                    if (truth == 0) {
                        stopped_by_callback = true;
                        run.cancel = true;
                    }
                }
            }
        } catch (...) {
            interruption = std::current_exception();
            run.cancel = true;
        }
    }
    worker.join();  // already finished: `done` was set last

    if (interruption) std::rethrow_exception(interruption);
    if (stopped_by_callback)
        raise_cancelled(std::string(what) + ": cancelled by the progress callback");
    if (!run.ok) raise_error(run.code, run.message);
    if (!progress.is_none()) progress(1.0);
}

py::object direct_lighting(const Scene& scene, const py::handle& points_in,
                           const py::handle& normals_in, const py::handle& techniques,
                           const py::handle& samples, int rounds, const std::string& strategy_name,
                           const py::handle& seed_in, double beta, double cutoff,
                           const py::object& progress, bool return_stats) {
    auto points = as_float_array(points_in, "points");
    auto normals = as_float_array(normals_in, "normals");
    if (points.ndim() != 2 || points.shape(1) != 3)
        bad("points", "expected shape (P, 3), got " + shape_of(points));
    const py::ssize_t P = points.shape(0);
    if (normals.ndim() != 2 || normals.shape(0) != P || normals.shape(1) != 3)
        bad("normals", "expected shape (" + std::to_string(P) + ", 3) like points, got " +
                           shape_of(normals));
    const TechniqueArgs t = technique_args(techniques, samples);
    OMISStrategy strategy;
    if (!omisParseStrategy(c_string(strategy_name, "strategy"), &strategy))
        bad("strategy", "unknown strategy '" + strategy_name +
                            "' (balance, power, maximum, cutoff, optimal-direct, "
                            "optimal-progressive)");
    std::uint64_t seed;
    {
        py::object index = py::reinterpret_steal<py::object>(PyNumber_Index(seed_in.ptr()));
        if (!index) {
            PyErr_Clear();
            bad("seed", "expected a non-negative integer");
        }
        seed = PyLong_AsUnsignedLongLong(index.ptr());
        if (PyErr_Occurred()) {
            PyErr_Clear();
            bad("seed", "expected an integer in [0, 2**64)");
        }
    }
    if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
        bad("progress", "expected a callable taking the fraction done");

    py::array_t<double> value({P, py::ssize_t(3)}), variance({P, py::ssize_t(3)});
    OMISDirectLightingStats stats{};
    run_interruptible("direct_lighting", progress, [&](NativeRun& run) {
        return omisDirectLighting(scene.get(), points.data(), normals.data(), size_t(P),
                                  t.names.c_str(), t.samples_ptr(), rounds, strategy, beta,
                                  cutoff, seed, value.mutable_data(), variance.mutable_data(),
                                  &stats, on_progress, &run);
    });
    if (!return_stats) return py::make_tuple(value, variance);
    py::dict d;
    d["points"] = stats.points;
    d["samples"] = stats.samples;
    d["rays_traced"] = stats.raysTraced;
    d["mis_systems"] = stats.misSystems;
    d["pdf_evaluations"] = stats.pdfEvaluations;
    d["seconds"] = stats.seconds;
    d["plan"] = plan_text(scene, t);
    return py::make_tuple(value, variance, d);
}

// ---- Baking ---------------------------------------------------------------

// A finished bake: arrays with row 0 at the bottom (Blender's Image.pixels
// order), statistics, and atomic file writers.
class BakeResult {
public:
    BakeResult(OMISBakeResult result, bool lightmap) : ref_(result), lightmap_(lightmap) {
        if (!omisGetBakeResultSize(ref_.get(), &width_, &height_)) raise_pending_error();
    }

    py::array value() const { return array("value", 3); }
    py::array noise() const { return array("noise", 1); }
    py::array mask() const { return array("mask", 1); }

    py::dict stats() const {
        OMISBakeStats s{};
        if (!omisGetBakeResultStats(ref_.get(), &s)) raise_pending_error();
        static const char* status[] = {"complete", "time budget reached", "noise target reached"};
        py::dict d;
        d["status"] = status[std::clamp(s.status, 0, 2)];
        d["seconds"] = s.seconds;
        d["samples"] = s.samples;
        d["rays_traced"] = s.raysTraced;
        d["samples_per_texel"] = s.samplesPerTexel;
        d["mean_relative_error"] = s.meanRelativeError;
        d["max_relative_error"] = s.maxRelativeError;
        d["passes"] = s.passes;
        d["texels"] = s.texels;
        d["covered"] = s.covered;
        d["degenerate_uv_triangles"] = s.degenerateUvTriangles;
        const size_t n = omisGetBakeResultPlan(ref_.get(), nullptr, 0);
        std::string plan(n + 1, '\0');
        omisGetBakeResultPlan(ref_.get(), &plan[0], plan.size());
        plan.resize(n);
        d["plan"] = plan;
        return d;
    }

    void write_exr(const std::string& path) const {
        bool ok;
        {
            py::gil_scoped_release release;
            ok = omisWriteBakeResultEXR(ref_.get(), c_string(path, "path"));
        }
        if (!ok) raise_pending_error();
    }

    void write_png(const std::string& path, const std::string& view, const std::string& display,
                   double exposure) const {
        c_string(path, "path");
        c_string(view, "view");
        c_string(display, "display");
        if (!std::isfinite(exposure)) bad("exposure", "must be a finite number of stops");
        bool ok;
        {
            py::gil_scoped_release release;
            ok = omisWriteBakeResultPNG(ref_.get(), path.c_str(), view.c_str(), display.c_str(),
                                        exposure);
        }
        if (!ok) raise_pending_error();
    }

    std::string repr() const {
        return "<omis.BakeResult " + std::to_string(width_) + "×" + std::to_string(height_) +
               (lightmap_ ? " lightmap>" : " points>");
    }

private:
    py::array array(const char* name, int channels) const {
        const float* data = omisGetBakeResultData(ref_.get(), name);
        if (!data) raise_pending_error();
        std::vector<py::ssize_t> shape;
        if (lightmap_) shape = {height_, width_};
        else shape = {width_};
        if (channels > 1) shape.push_back(channels);
        py::array_t<float> out(shape);
        std::memcpy(out.mutable_data(), data, sizeof(float) * size_t(out.size()));
        return std::move(out);
    }

    omis::capi::BakeResultRef ref_;
    bool lightmap_;
    int width_ = 0, height_ = 0;
};

std::uint64_t seed_value(const py::handle& seed_in) {
    py::object index = py::reinterpret_steal<py::object>(PyNumber_Index(seed_in.ptr()));
    if (!index) {
        PyErr_Clear();
        bad("seed", "expected a non-negative integer");
    }
    const std::uint64_t seed = PyLong_AsUnsignedLongLong(index.ptr());
    if (PyErr_Occurred()) {
        PyErr_Clear();
        bad("seed", "expected an integer in [0, 2**64)");
    }
    return seed;
}

struct BakeOptions {
    py::object techniques, counts;
    long long samples;
    std::string strategy;
    double beta, cutoff;
    py::object time_budget, noise_target;
    py::object seed;
    bool smooth_normals;
    py::object progress;
    int threads;
    std::string margin_type = "extend";   // lightmaps: "extend" or "adjacent-faces"
};

BakeResult run_bake(const Scene& scene, unsigned int mesh, OMISBakeTarget target, int width,
                    int height, int margin, const BakeOptions& o) {
    if (!o.progress.is_none() && !PyCallable_Check(o.progress.ptr()))
        bad("progress", "expected a callable taking the fraction done");
    omis::capi::BakeRef bake(omisNewBake(scene.get(), target, mesh));
    if (!bake) raise_pending_error();
    OMISBake b = bake.get();
    auto check = [] {
        const char* message = nullptr;
        const OMISError code = omisGetError(&message);
        if (code != OMIS_ERROR_NONE) raise_error(code, message ? message : "bake: error");
    };
    if (target == OMIS_BAKE_LIGHTMAP) {
        if (width < 1 || height < 1)
            bad("width, height", "must be positive, got " + std::to_string(width) + "×" +
                                     std::to_string(height));
        omisSetBakeInt(b, "width", width);
        omisSetBakeInt(b, "height", height);
        if (margin < 0) bad("margin", "must not be negative");
        omisSetBakeInt(b, "margin", margin);
        if (o.margin_type != "extend" && o.margin_type != "adjacent-faces")
            bad("margin_type", "expected 'extend' or 'adjacent-faces', got '" + o.margin_type + "'");
        omisSetBakeString(b, "marginType", o.margin_type.c_str());
    }
    if (o.samples < 1) bad("samples", "the sample budget must be at least 1");
    omisSetBakeInt(b, "samples", o.samples);
    omisSetBakeInt(b, "seed", std::int64_t(seed_value(o.seed)));
    omisSetBakeInt(b, "smoothNormals", o.smooth_normals);
    if (o.threads < 0) bad("threads", "must be ≥ 0 (0 = all cores)");
    omisSetBakeInt(b, "threads", o.threads);
    omisSetBakeString(b, "strategy", c_string(o.strategy, "strategy"));
    omisSetBakeFloat(b, "beta", o.beta);
    omisSetBakeFloat(b, "cutoff", o.cutoff);
    if (!o.time_budget.is_none()) {
        const double t = number_arg(o.time_budget, "time_budget");
        if (!(t > 0) || !std::isfinite(t)) bad("time_budget", "expected seconds > 0, or None");
        omisSetBakeFloat(b, "timeBudget", t);
    }
    if (!o.noise_target.is_none()) {
        const double t = number_arg(o.noise_target, "noise_target");
        if (!(t > 0) || !std::isfinite(t))
            bad("noise_target", "expected a relative standard error > 0, or None");
        omisSetBakeFloat(b, "noiseTarget", t);
    }
    if (o.techniques.is_none()) {
        if (!o.counts.is_none())
            bad("counts", "given without techniques (techniques=None lets the effect plan "
                          "choose techniques and counts)");
    } else {
        // One count per technique per round, 1 each unless given.
        py::object counts = o.counts;
        if (counts.is_none()) {
            std::size_t n;
            if (py::isinstance<py::str>(o.techniques)) {
                const std::string list = o.techniques.cast<std::string>();
                n = 1 + std::count(list.begin(), list.end(), ',');
            } else {
                n = py::len(o.techniques);
            }
            py::array_t<int> ones(static_cast<py::ssize_t>(n));
            std::fill(ones.mutable_data(), ones.mutable_data() + n, 1);
            counts = std::move(ones);
        }
        TechniqueArgs t;
        try {
            t = technique_args(o.techniques, counts);
        } catch (const py::value_error& e) {
            // technique_args names `samples`; here the per-round counts are `counts`.
            std::string message = e.what();
            if (message.rfind("samples:", 0) == 0) message = "counts:" + message.substr(8);
            throw py::value_error(message);
        }
        long long per_round = 0;
        for (std::size_t k = 0; k < t.samples.size(); ++k) {
            if (t.samples[k] < 0) bad("counts", "entry " + std::to_string(k) + " is negative");
            per_round += t.samples[k];
        }
        // samples is the per-texel budget, spent in whole rounds of sum(counts);
        // counts the caller wrote must fit it (default counts: at least one round).
        if (!o.counts.is_none() && per_round > o.samples)
            bad("samples", "the budget of " + std::to_string(o.samples) +
                               " per texel is less than one round of counts (" +
                               std::to_string(per_round) + "); raise samples or lower counts");
        omisSetBakeString(b, "techniques", t.names.c_str());
        omisSetBakeCounts(b, t.samples.data(), int(t.samples.size()));
    }
    check();
    omisCommitBake(b);
    check();

    OMISBakeResult result = nullptr;
    run_interruptible("bake", o.progress, [&](NativeRun& run) {
        omisSetBakeProgressFunction(b, on_progress, &run);
        result = omisExecuteBake(b);
        return result != nullptr;
    });
    return BakeResult(result, target == OMIS_BAKE_LIGHTMAP);
}

BakeResult bake_uv(const Scene& scene, unsigned int mesh, int width, int height,
                   const py::object& techniques, const py::object& counts, long long samples,
                   const std::string& strategy, double beta, double cutoff,
                   const py::object& time_budget, const py::object& noise_target, int margin,
                   const py::object& seed, bool smooth_normals, const py::object& progress,
                   int threads, const std::string& margin_type) {
    return run_bake(scene, mesh, OMIS_BAKE_LIGHTMAP, width, height, margin,
                    {techniques, counts, samples, strategy, beta, cutoff, time_budget,
                     noise_target, seed, smooth_normals, progress, threads, margin_type});
}

BakeResult bake_vertices(const Scene& scene, unsigned int mesh, const std::string& domain,
                         const py::object& techniques, const py::object& counts,
                         long long samples, const std::string& strategy, double beta,
                         double cutoff, const py::object& time_budget,
                         const py::object& noise_target, const py::object& seed,
                         bool smooth_normals, const py::object& progress, int threads) {
    OMISBakeTarget target;
    if (domain == "POINT") target = OMIS_BAKE_VERTICES;
    else if (domain == "CORNER") target = OMIS_BAKE_CORNERS;
    else bad("domain", "expected 'POINT' or 'CORNER', got '" + domain + "'");
    return run_bake(scene, mesh, target, 0, 0, 0,
                    {techniques, counts, samples, strategy, beta, cutoff, time_budget,
                     noise_target, seed, smooth_normals, progress, threads});
}

}  // namespace

PYBIND11_MODULE(_omis, m) {
    m.doc() = "omis native module (pybind11 over the omis C ABI)";
    m.attr("__version__") = OMIS_VERSION_STRING;
    if (omisGetVersion() != OMIS_VERSION)
        throw std::runtime_error("omis: the loaded libomis does not match this module's version");
    m.attr("STRATEGIES") = py::make_tuple("balance", "power", "maximum", "cutoff",
                                          "optimal-direct", "optimal-progressive");
    m.def("combine", &combine, py::arg("f"), py::arg("pdfs"), py::arg("technique"),
          py::arg("counts"), py::arg("strategy") = "optimal-direct",
          R"doc(Combines samples of N techniques with a MIS strategy (SPEC §6).

f: (S,) or (S, C) integrand values; pdfs: (S, N) densities of every technique at
every sample; technique: (S,) which technique drew each sample; counts: (N,)
samples of each technique per round, samples ordered round by round.
strategy: balance | power | maximum | cutoff | optimal-direct | optimal-progressive.
Options: beta (power), cutoff (cutoff), return_variance.
Returns (C,) estimates, or (estimates, variances) with return_variance=True.)doc");

    g_cancelled = PyErr_NewExceptionWithDoc(
        "omis.Cancelled", "A long call stopped because its progress callable returned False.",
        PyExc_RuntimeError, nullptr);
    if (!g_cancelled) throw py::error_already_set();
    m.add_object("Cancelled", py::handle(g_cancelled));  // the module keeps it alive

    const double pi = 3.14159265358979323846;
    py::class_<Scene>(m, "Scene", R"doc(Meshes and lights for direct lighting (SPEC §3–§4).

Add meshes and lights, commit(), then light it with omis.direct_lighting.
Units: metres; radiance W/(m² sr), intensity W/sr, irradiance W/m² (RGB: three
numbers, or one for grey); angles in radians. Every add returns an integer id.)doc")
        .def(py::init<>())
        .def("add_mesh", &Scene::add_mesh, py::arg("vertices"), py::arg("triangles"),
             py::arg("normals") = py::none(), py::arg("uvs") = py::none(),
             py::arg("emission") = py::none(),
             R"doc(Adds a triangle mesh (an occluder; also an emitter with emission).

vertices: (V, 3) float32/float64; triangles: (T, 3) integer vertex indices,
counter-clockwise = front; normals: optional (3T, 3) per-corner shading
normals; uvs: optional (3T, 2) per-corner UVs; emission: optional RGB radiance
(the mesh then emits from both sides). Returns the mesh id.)doc")
        .def("add_rect_light", &Scene::add_rect_light, py::arg("corner"), py::arg("edge_u"),
             py::arg("edge_v"), py::arg("radiance"), py::arg("two_sided") = false,
             py::arg("spread") = pi,
             "Rectangle corner + [0,1]·edge_u + [0,1]·edge_v (perpendicular edges); "
             "one-sided lights emit toward cross(edge_u, edge_v). Returns the light id.")
        .def("add_ellipse_light", &Scene::add_ellipse_light, py::arg("center"),
             py::arg("axis_u"), py::arg("axis_v"), py::arg("radiance"),
             py::arg("two_sided") = false, py::arg("spread") = pi,
             "Ellipse center + a·axis_u + b·axis_v, a² + b² ≤ 1 (perpendicular semi-axes); "
             "one-sided lights emit toward cross(axis_u, axis_v). Returns the light id.")
        .def("add_disk_light", &Scene::add_disk_light, py::arg("center"), py::arg("normal"),
             py::arg("radius"), py::arg("radiance"), py::arg("two_sided") = false,
             py::arg("spread") = pi,
             "Disk of the given radius emitting along normal (both ways if two_sided). "
             "Returns the light id.")
        .def("add_point_light", &Scene::add_point_light, py::arg("position"),
             py::arg("intensity"), py::arg("radius") = 0.0,
             "Point light of intensity W/sr; radius > 0 makes it a disk facing the receiver. "
             "Returns the light id.")
        .def("add_spot_light", &Scene::add_spot_light, py::arg("position"), py::arg("direction"),
             py::arg("intensity"), py::arg("spot_size"), py::arg("spot_blend") = 0.15,
             py::arg("radius") = 0.0,
             "Spot light shining along direction; spot_size is the full cone angle, "
             "spot_blend Blender's smoothstep width in [0, 1]. Returns the light id.")
        .def("add_sun_light", &Scene::add_sun_light, py::arg("direction"), py::arg("irradiance"),
             py::arg("angle") = 0.0,
             "Sun light travelling along direction; irradiance on a surface facing it; angle "
             "is the full angular diameter (0: one shadow ray). Returns the light id.")
        .def("set_world", &Scene::set_world, py::arg("radiance"),
             "Constant background radiance from every direction (replaces an earlier one). "
             "Returns the light id.")
        .def("set_light_flags", &Scene::set_light_flags, py::arg("light"),
             py::arg("cast_shadow") = true, py::arg("visible_to_bsdf") = true,
             "Blender's cycles.cast_shadow and use_multiple_importance_sampling for one light.")
        .def("set_receiver", &Scene::set_receiver, py::arg("mesh"), py::arg("model"),
             py::arg("roughness") = 0.0,
             "The mesh's diffuse closure when baked, as Cycles' Diffuse bake evaluates it: "
             "'lambert' (default), 'principled' (Principled BSDF, its Roughness) or "
             "'oren-nayar' (Diffuse BSDF, its Roughness). Before commit.")
        .def("commit", &Scene::commit,
             "Builds the acceleration structure; the scene is then read-only.")
        .def("effect_plan", &effect_plan, py::arg("techniques") = py::none(),
             py::arg("samples") = py::none(),
             "The effect plan of the committed scene for these techniques (None: the "
             "default choice), as printable text.");

    m.def("direct_lighting", &direct_lighting, py::arg("scene"), py::arg("points"),
          py::arg("normals"), py::arg("techniques") = py::none(), py::arg("samples") = py::none(),
          py::arg("rounds") = 1, py::arg("strategy") = "optimal-direct", py::arg("seed") = 0,
          py::kw_only(), py::arg("beta") = 2.0, py::arg("cutoff") = 0.1,
          py::arg("progress") = py::none(), py::arg("return_stats") = false,
          R"doc(E_direct/π per RGB channel at shading points of a committed scene (SPEC §3, §6).

points, normals: (P, 3) float arrays (normals are normalised; not zero).
techniques: list of names ("bsdf", "<uniform|power|unoccluded|tree>/<area|solid-angle|parallel>")
or one comma-separated string, with samples: one count per technique per round;
techniques=None lets the effect plan choose both (samples must then be None).
rounds: R; strategy: a MIS strategy name (see STRATEGIES); seed: results depend on
it only, not on the thread count. beta, cutoff: heuristic options.
progress: optional callable, called with the fraction done about every 50 ms on
the calling thread (and with 1.0 at the end); returning False stops the work and
raises omis.Cancelled. Ctrl-C stops it too (KeyboardInterrupt).
Returns (value, variance), (P, 3) float64 arrays, plus a stats dict (points,
samples, rays_traced, mis_systems, pdf_evaluations, seconds, plan) with
return_stats=True.)doc");

    py::class_<BakeResult>(m, "BakeResult",
                           "A finished bake: value, noise and mask arrays (row 0 at the bottom, "
                           "as Blender's Image.pixels), stats, and atomic file writers.")
        .def_property_readonly("value", &BakeResult::value,
                               "E_direct/π, float32 (H, W, 3), or (count, 3) for vertex bakes")
        .def_property_readonly("noise", &BakeResult::noise,
                               "estimated relative standard error per texel")
        .def_property_readonly("mask", &BakeResult::mask, "1 where baked, 0 margin or empty")
        .def_property_readonly("stats", &BakeResult::stats,
                               "time, samples, rays, errors, passes, status and the effect plan")
        .def("write_exr", &BakeResult::write_exr, py::arg("path"),
             "Linear float EXR with channels R, G, B, noise, mask (atomic write).")
        .def("write_png", &BakeResult::write_png, py::arg("path"), py::arg("view") = "Standard",
             py::arg("display") = "sRGB", py::arg("exposure") = 0.0,
             "8-bit PNG through Blender's OCIO view transform (atomic write).")
        .def("__repr__", &BakeResult::repr);

    m.def("bake_uv", &bake_uv, py::arg("scene"), py::arg("mesh"), py::arg("width"),
          py::arg("height"), py::kw_only(), py::arg("techniques") = py::none(),
          py::arg("counts") = py::none(), py::arg("samples") = 64,
          py::arg("strategy") = "optimal-direct", py::arg("beta") = 2.0, py::arg("cutoff") = 0.1,
          py::arg("time_budget") = py::none(), py::arg("noise_target") = py::none(),
          py::arg("margin") = 16, py::arg("seed") = 0, py::arg("smooth_normals") = true,
          py::arg("progress") = py::none(), py::arg("threads") = 0,
          py::arg("margin_type") = "extend",
          R"doc(Bakes E_direct/π into a mesh's UV lightmap of width × height texels.

techniques: names (SPEC §3) or None for the effect plan's choice; counts: samples
of each technique per round (1 each by default); samples: the sample budget per
texel, spent in whole rounds of sum(counts) (rounded down, at least one round; given
counts whose round exceeds samples are an error). time_budget (s) and noise_target (relative standard error) stop the bake
earlier. progress(fraction) -> bool is called on this thread; False or Ctrl-C
raises omis.Cancelled / KeyboardInterrupt and nothing is returned. threads: worker
threads (0 = all cores); results do not depend on it. margin (texels) and
margin_type fill the texels around UV islands as Blender's Bake ▸ Margin does:
'extend' copies the island's nearest texel, 'adjacent-faces' the texel across
the UV seam on the face adjacent in 3D (extend where there is none).)doc");
    m.def("bake_vertices", &bake_vertices, py::arg("scene"), py::arg("mesh"), py::kw_only(),
          py::arg("domain") = "POINT", py::arg("techniques") = py::none(),
          py::arg("counts") = py::none(), py::arg("samples") = 64,
          py::arg("strategy") = "optimal-direct", py::arg("beta") = 2.0, py::arg("cutoff") = 0.1,
          py::arg("time_budget") = py::none(), py::arg("noise_target") = py::none(),
          py::arg("seed") = 0, py::arg("smooth_normals") = true, py::arg("progress") = py::none(),
          py::arg("threads") = 0,
          R"doc(Bakes E_direct/π at a mesh's vertices (domain "POINT") or triangle corners
("CORNER", 3 per triangle in triangle order), as bake_uv does for texels. As in
Cycles, each corner is shaded just inside its triangle and a vertex takes the
mean of its corners.)doc");
}
