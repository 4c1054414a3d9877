// Header-only C++ convenience over the C ABI (as oidn.hpp does for OIDN):
// handles are RAII (copy = retain, destructor = release), errors become
// exceptions carrying the C error code.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>

#include "omis/omis.h"

namespace omis::capi {

class Error : public std::runtime_error {
public:
    Error(OMISError code, const std::string& message)
        : std::runtime_error(message), code_(code) {}
    OMISError code() const { return code_; }

private:
    OMISError code_;
};

// Throws the thread's pending error, if any.
inline void throw_if_error() {
    const char* message = nullptr;
    const OMISError code = omisGetError(&message);
    if (code != OMIS_ERROR_NONE) throw Error(code, message ? message : "omis error");
}

template <class Handle, void (*Retain)(Handle), void (*Release)(Handle)>
class Ref {
public:
    Ref() = default;
    explicit Ref(Handle h) : h_(h) {}  // adopts the reference
    Ref(const Ref& o) : h_(o.h_) {
        if (h_) Retain(h_);
    }
    Ref(Ref&& o) noexcept : h_(std::exchange(o.h_, nullptr)) {}
    Ref& operator=(Ref o) noexcept {
        std::swap(h_, o.h_);
        return *this;
    }
    ~Ref() {
        if (h_) Release(h_);
    }
    Handle get() const { return h_; }
    explicit operator bool() const { return h_ != nullptr; }

private:
    Handle h_ = nullptr;
};

using EstimatorRef = Ref<OMISEstimator, omisRetainEstimator, omisReleaseEstimator>;
using SceneRef = Ref<OMISScene, omisRetainScene, omisReleaseScene>;
using DirectLightingRef =
    Ref<OMISDirectLighting, omisRetainDirectLighting, omisReleaseDirectLighting>;
using BakeRef = Ref<OMISBake, omisRetainBake, omisReleaseBake>;
using BakeResultRef = Ref<OMISBakeResult, omisRetainBakeResult, omisReleaseBakeResult>;

}  // namespace omis::capi
