// RAII owner of the Embree device. Embree reports errors through a C callback;
// throwing from inside it would unwind through Embree's C frames, so the
// callback only records the error and check() turns it into an exception.
#pragma once

#include <embree3/rtcore.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace omis {

// An Embree error, carrying Embree's code and message.
class EmbreeError : public std::runtime_error {
public:
    EmbreeError(RTCError code, const std::string& message)
        : std::runtime_error(message), code_(code) {}
    RTCError code() const { return code_; }

private:
    RTCError code_;
};

class Device {
public:
    // `config` is Embree's device configuration string ("" = defaults).
    explicit Device(const std::string& config = "");
    ~Device();
    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;

    // One device per process is enough; scenes share it through this.
    static std::shared_ptr<Device> shared();

    RTCDevice handle() const { return device_; }

    // Throws EmbreeError with the first error recorded since the last check
    // (from any thread, including Embree's build threads), and clears it.
    void check() const;
    // Cheap test used on hot paths before paying for check().
    bool has_error() const { return has_error_.load(std::memory_order_acquire); }

    // Human-readable name of an Embree error code.
    static const char* error_name(RTCError code);

private:
    static void on_error(void* user, RTCError code, const char* message);

    RTCDevice device_ = nullptr;
    mutable std::mutex mutex_;
    mutable std::atomic<bool> has_error_{false};
    mutable RTCError code_ = RTC_ERROR_NONE;
    mutable std::string message_;
};

// A new (uncommitted) Embree geometry of unindexed triangles, three vertices
// of three floats each in `vertices`; throws naming `who` where Embree cannot
// allocate the buffers.
RTCGeometry new_triangle_soup(const Device& device, const std::vector<float>& vertices,
                              const std::string& who);

}  // namespace omis
