#include "scene/device.h"

#include <algorithm>
#include <cstdint>

namespace omis {

const char* Device::error_name(RTCError code) {
    switch (code) {
        case RTC_ERROR_NONE: return "RTC_ERROR_NONE";
        case RTC_ERROR_UNKNOWN: return "RTC_ERROR_UNKNOWN";
        case RTC_ERROR_INVALID_ARGUMENT: return "RTC_ERROR_INVALID_ARGUMENT";
        case RTC_ERROR_INVALID_OPERATION: return "RTC_ERROR_INVALID_OPERATION";
        case RTC_ERROR_OUT_OF_MEMORY: return "RTC_ERROR_OUT_OF_MEMORY";
        case RTC_ERROR_UNSUPPORTED_CPU: return "RTC_ERROR_UNSUPPORTED_CPU";
        case RTC_ERROR_CANCELLED: return "RTC_ERROR_CANCELLED";
    }
    return "RTC_ERROR_?";
}

Device::Device(const std::string& config) {
    device_ = rtcNewDevice(config.empty() ? nullptr : config.c_str());
    if (!device_) {
        const RTCError code = rtcGetDeviceError(nullptr);
        throw EmbreeError(code, std::string("Embree: cannot create device (") +
                                    error_name(code) + ") with config \"" + config +
                                    "\"");
    }
    rtcSetDeviceErrorFunction(device_, &Device::on_error, this);
}

Device::~Device() {
    if (device_) rtcReleaseDevice(device_);
}

std::shared_ptr<Device> Device::shared() {
    // Created on first use, destroyed after the last scene that holds it.
    static std::mutex mutex;
    static std::weak_ptr<Device> instance;
    std::lock_guard<std::mutex> lock(mutex);
    std::shared_ptr<Device> device = instance.lock();
    if (!device) {
        device = std::make_shared<Device>();
        instance = device;
    }
    return device;
}

void Device::on_error(void* user, RTCError code, const char* message) {
    auto* self = static_cast<Device*>(user);
    std::lock_guard<std::mutex> lock(self->mutex_);
    if (self->has_error_.load(std::memory_order_relaxed)) return;  // keep the first
    self->code_ = code;
    self->message_ = message ? message : "";
    self->has_error_.store(true, std::memory_order_release);
}

void Device::check() const {
    if (!has_error_.load(std::memory_order_acquire)) return;
    RTCError code;
    std::string message;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        code = code_;
        message.swap(message_);
        code_ = RTC_ERROR_NONE;
        has_error_.store(false, std::memory_order_release);
    }
    throw EmbreeError(code, std::string("Embree error ") + error_name(code) + ": " + message);
}

RTCGeometry new_triangle_soup(const Device& device, const std::vector<float>& vertices,
                              const std::string& who) {
    const std::size_t triangles = vertices.size() / 9;
    RTCGeometry geom = rtcNewGeometry(device.handle(), RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * triangles));
    auto* ib = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), triangles));
    if (!vb || !ib) {
        rtcReleaseGeometry(geom);
        device.check();
        throw std::runtime_error(who + ": Embree could not allocate buffers");
    }
    std::copy(vertices.begin(), vertices.begin() + 9 * triangles, vb);
    for (std::uint32_t i = 0; i < 3 * triangles; ++i) ib[i] = i;
    return geom;
}

}  // namespace omis
