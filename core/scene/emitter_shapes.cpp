#include "scene/emitter_shapes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace omis {
namespace {

// Relative growth of every shape about its centroid: far above float's
// rounding (1e-7), far below any light's size.
constexpr double kEnlarge = 1e-3;

// An occlusion query whose filter records every light and rejects the hit,
// so that Embree goes on to the next one.
struct CollectContext {
    RTCIntersectContext context;  // first: Embree hands filters this pointer
    const std::uint32_t* light_of;
    std::vector<std::uint32_t>* out;
};

void collect(const RTCFilterFunctionNArguments* args) {
    auto* c = reinterpret_cast<CollectContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        c->out->push_back(c->light_of[RTCHitN_primID(args->hit, args->N, i)]);
        args->valid[i] = 0;
    }
}

}  // namespace

EmitterShapes::EmitterShapes(std::shared_ptr<Device> device) : device_(std::move(device)) {}

EmitterShapes::~EmitterShapes() {
    if (scene_) rtcReleaseScene(scene_);
}

void EmitterShapes::add_triangle(std::uint32_t light, const Vec3& a, const Vec3& b,
                                 const Vec3& c) {
    if (committed_) throw std::logic_error("emitter shapes: already committed");
    const Vec3 centroid = (a + b + c) / 3.0;
    for (const Vec3& p : {a, b, c}) {
        const Vec3 q = centroid + (p - centroid) * (1 + kEnlarge);
        vertices_.insert(vertices_.end(), {float(q.x), float(q.y), float(q.z)});
    }
    light_of_.push_back(light);
}

void EmitterShapes::commit() {
    if (committed_) return;
    committed_ = true;
    if (empty()) return;
    scene_ = rtcNewScene(device_->handle());
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = new_triangle_soup(*device_, vertices_, "emitter shapes");
    rtcSetGeometryOccludedFilterFunction(geom, collect);
    // Static shapes queried by every sample: spatial splits pay back.
    rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_HIGH);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene_);
    device_->check();
    vertices_ = {};
}

void EmitterShapes::lights_along(const Vec3& origin, const Vec3& direction,
                                 std::vector<std::uint32_t>& out, double tmax) const {
    if (!committed_) throw std::logic_error("emitter shapes: lights_along before commit");
    if (!scene_) return;
    RTCRay ray;
    ray.org_x = float(origin.x); ray.org_y = float(origin.y); ray.org_z = float(origin.z);
    ray.dir_x = float(direction.x); ray.dir_y = float(direction.y); ray.dir_z = float(direction.z);
    ray.tnear = 0.0f;
    ray.tfar = tmax < double(std::numeric_limits<float>::max())
                   ? std::nextafter(float(tmax), std::numeric_limits<float>::infinity())
                   : std::numeric_limits<float>::infinity();
    ray.time = 0.0f;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    CollectContext c;
    rtcInitIntersectContext(&c.context);
    c.light_of = light_of_.data();
    const std::size_t first = out.size();
    c.out = &out;
    rtcOccluded1(scene_, &c.context, &ray);
    // A light of several triangles (a rect, an ellipse) may be crossed twice.
    std::sort(out.begin() + first, out.end());
    out.erase(std::unique(out.begin() + first, out.end()), out.end());
}

}  // namespace omis
