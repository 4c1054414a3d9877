// Shared by the parts of the omis._omis module: C errors as Python exceptions,
// and argument conversions whose errors name the argument the caller wrote.
#pragma once

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

namespace omis_py {

// omis.Cancelled, created at import.
inline PyObject* g_cancelled = nullptr;

[[noreturn]] inline void raise_cancelled(const std::string& message) {
    PyErr_SetString(g_cancelled, message.c_str());
    throw py::error_already_set();
}

// Turns a C error into the Python exception users expect.
[[noreturn]] inline void raise_error(OMISError code, const std::string& message) {
    if (code == OMIS_ERROR_INVALID_ARGUMENT) throw py::value_error(message);
    if (code == OMIS_ERROR_CANCELLED) raise_cancelled(message);
    if (code == OMIS_ERROR_NONE)
        throw std::runtime_error("omis: call failed without an error message");
    throw std::runtime_error(message);
}

// Turns the thread's pending C error into a Python exception.
[[noreturn]] inline void raise_pending_error() {
    const char* message = nullptr;
    const OMISError code = omisGetError(&message);
    raise_error(code, message ? message : "omis error");
}

// After a void call: raises the error it left, if any.
inline void raise_if_pending() {
    const char* message = nullptr;
    const OMISError code = omisGetError(&message);
    if (code != OMIS_ERROR_NONE) raise_error(code, message ? message : "omis error");
}

[[noreturn]] inline void bad(const std::string& argument, const std::string& problem) {
    throw py::value_error(argument + ": " + problem);
}

inline std::string type_name(const py::handle& obj) {
    return py::str(py::type::handle_of(obj).attr("__name__"));
}

// Keyword values checked here, so a wrong type names the argument instead of
// pybind11's "Unable to cast Python instance to C++ type".
inline bool bool_arg(const py::handle& obj, const char* name) {
    if (py::isinstance<py::bool_>(obj)) return obj.cast<bool>();
    if (type_name(obj) == "bool_") return py::bool_(py::reinterpret_borrow<py::object>(obj));
    throw py::type_error(std::string(name) + ": expected True or False, got " + type_name(obj));
}

inline double number_arg(const py::handle& obj, const char* name) {
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

// A seed: any integer in [0, 2**64) (numpy integers too).
inline std::uint64_t seed_value(const py::handle& seed_in) {
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

// A string for the C ABI, which would stop at an embedded NUL ('a\0.exr' → 'a').
inline const char* c_string(const std::string& text, const char* name) {
    if (text.find('\0') != std::string::npos) bad(name, "contains a NUL byte");
    return text.c_str();
}

inline std::string shape_of(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i)
        s += (i ? ", " : "") + std::to_string(a.shape(i));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

// A C-contiguous float64 view of a floating-point array; other dtypes are refused.
inline py::array_t<double, py::array::c_style | py::array::forcecast> as_float_array(const py::handle& obj,
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

inline py::array_t<int, py::array::c_style | py::array::forcecast> as_int_array(const py::handle& obj, const char* name) {
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

// ---- Small values and (rows, cols) arrays ----------------------------------

using Triple = std::array<double, 3>;

// Any sequence of 3 real numbers; with `grey`, a single number means (v, v, v).
inline Triple triple(const py::handle& obj, const char* name, bool grey = false) {
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

inline double finite(double v, const char* name) {
    if (!std::isfinite(v)) bad(name, "must be finite");
    return v;
}

// A light id, or the pending error.
inline unsigned int checked_id(unsigned int id) {
    if (id == OMIS_INVALID_ID) raise_pending_error();
    return id;
}

inline void check_rows_finite(const py::array& a, const char* name) {
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
inline py::array float_rows(const py::handle& obj, const char* name, py::ssize_t rows, py::ssize_t cols,
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

}  // namespace omis_py
