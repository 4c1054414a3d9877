// The progress throttle every lighting job shares: a cancel check may come
// at every few hundred samples from any thread, but the caller's progress
// function (a Python callable, Blender's UI) is called at most every 50 ms.
#pragma once

#include <atomic>

namespace omis {

class ProgressThrottle {
public:
    static constexpr double kInterval = 0.05;  // seconds between reports
    // Whether a report is due at `now` (seconds of the job's clock); if so,
    // the next is due kInterval later. Any thread.
    bool due(double now) {
        if (!(now - last_.load(std::memory_order_relaxed) >= kInterval)) return false;
        last_ = now;
        return true;
    }

private:
    std::atomic<double> last_{0};
};

}  // namespace omis
