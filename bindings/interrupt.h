// Long native calls from Python: run on a worker thread while the calling
// thread reports progress and notices Ctrl-C.
#pragma once

#include "common.h"

namespace omis_py {

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
inline bool on_progress(void* user, double fraction) {
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
inline void run_interruptible(const char* what, const py::object& progress,
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

}  // namespace omis_py
