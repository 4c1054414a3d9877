// Shared machinery of the C ABI: per-thread errors, reference counting and the
// exception barrier every exported function runs inside.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstring>
#include <exception>
#include <functional>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "mis/strategy.h"
#include "omis/omis.h"
#include "mis/estimator.h"

// Writes text into a caller's buffer as the ABI's text queries promise: at
// most size bytes with the terminating NUL (nothing when size is 0); returns
// the full length without the NUL.
inline std::size_t copy_text(const std::string& text, char* buffer, std::size_t size) {
    if (buffer && size > 0) {
        const std::size_t n = text.size() < size - 1 ? text.size() : size - 1;
        std::memcpy(buffer, text.data(), n);
        buffer[n] = '\0';
    }
    return text.size();
}

// The ABI's published limits are the core's own.
static_assert(OMIS_MAX_TECHNIQUES == omis::kMaxMisTechniques, "OMIS_MAX_TECHNIQUES");
static_assert(OMIS_MAX_CHANNELS == omis::kMaxMisChannels, "OMIS_MAX_CHANNELS");

namespace omis::api {

// An error with an explicit C code (wrong call order, cancellation, ...).
struct ApiError : std::runtime_error {
    OMISError code;
    ApiError(OMISError c, const std::string& message) : std::runtime_error(message), code(c) {}
};

void record_error(OMISError code, const char* message);

// Runs body; turns any exception into a recorded error and returns fallback.
template <class Fallback, class Body>
Fallback guarded(Fallback fallback, Body&& body) {
    try {
        return body();
    } catch (const ApiError& e) {
        record_error(e.code, e.what());
    } catch (const std::invalid_argument& e) {
        record_error(OMIS_ERROR_INVALID_ARGUMENT, e.what());
    } catch (const std::logic_error& e) {
        record_error(OMIS_ERROR_INVALID_OPERATION, e.what());
    } catch (const std::bad_alloc&) {
        record_error(OMIS_ERROR_OUT_OF_MEMORY, "out of memory");
    } catch (const std::exception& e) {
        record_error(OMIS_ERROR_UNKNOWN, e.what());
    } catch (...) {
        record_error(OMIS_ERROR_UNKNOWN, "unknown error");
    }
    return fallback;
}

template <class Body>
void guarded_void(Body&& body) {
    guarded(0, [&] {
        body();
        return 0;
    });
}

// Base of every handle: an intrusive reference count and a tag naming the
// handle's kind, checked on entry and cleared on release, so a released or
// foreign handle is reported instead of used — as far as its memory still
// reads back: after a release that memory may be reused, so use after release
// stays undefined behaviour that the tag only usually catches.
struct RefCounted {
    std::atomic<int> references{1};
    std::uint32_t tag = 0;
    virtual ~RefCounted() { tag = 0; }
};

// A handle type with its own tag (four ASCII letters).
template <std::uint32_t Tag>
struct Tagged : RefCounted {
    static constexpr std::uint32_t kTag = Tag;
    Tagged() { tag = Tag; }
};

// The tag of what may be no handle at all: exempt from UBSan's vptr check,
// which would flag exactly the misuse this looks for.
__attribute__((no_sanitize("vptr"))) inline std::uint32_t tag_of(const RefCounted* handle) {
    return handle->tag;
}

template <class T>
T* checked(T* handle, const char* what) {
    if (!handle) throw std::invalid_argument(std::string(what) + ": handle is NULL");
    if constexpr (std::is_base_of_v<RefCounted, T>) {
        if (tag_of(handle) != T::kTag)
            throw std::invalid_argument(std::string(what) +
                                        ": not a live handle of this kind (released, or foreign)");
    }
    return handle;
}

// The integer a C caller passed for an enum. C enums are ints; loading a value
// outside the C++ enum's range as that enum type is undefined, so the integer
// is read and checked before any conversion.
template <class E>
int enum_value(const E& value) {
    static_assert(sizeof(E) == sizeof(int), "C enums are int-sized");
    int v;
    std::memcpy(&v, &value, sizeof v);
    return v;
}

// The core strategy for a C enum value; std::invalid_argument outside the enum.
omis::Strategy to_core(const OMISStrategy& strategy);  // by reference: see enum_value

inline void retain(RefCounted* object) { object->references.fetch_add(1); }
inline void release(RefCounted* object) {
    if (object->references.fetch_sub(1) == 1) {
        object->tag = 0;
        delete object;
    }
}

// A job's per-round sample counts as the C caller passed them (copied).
inline std::vector<int> counts_argument(const int* counts, int numCounts) {
    if (numCounts < 0) throw std::invalid_argument("numCounts: must not be negative");
    if (numCounts > 0) checked(counts, "counts");
    return std::vector<int>(counts, counts + numCounts);
}

// A job's progress function: may be replaced while other threads execute the
// job, each of which takes the one set when it starts.
class ProgressSlot {
public:
    void set(OMISProgressFunction function, void* user) {
        std::lock_guard<std::mutex> lock(mutex_);
        function_ = function;
        user_ = user;
    }
    std::function<bool(double)> get() const {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!function_) return nullptr;
        return [function = function_, user = user_](double fraction) {
            return function(user, fraction);
        };
    }

private:
    mutable std::mutex mutex_;
    OMISProgressFunction function_ = nullptr;
    void* user_ = nullptr;
};

// The bodies of omisRetainX and omisReleaseX.
template <class T>
void retain_handle(T* handle, const char* what) {
    guarded_void([&] { retain(checked(handle, what)); });
}
template <class T>
void release_handle(T* handle, const char* what) {
    guarded_void([&] { release(checked(handle, what)); });
}

}  // namespace omis::api
