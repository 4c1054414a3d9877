#include "api_common.h"

#include <mutex>

namespace omis::api {
namespace {

struct ThreadError {
    OMISError code = OMIS_ERROR_NONE;
    std::string message;
    std::string returned;  // what omisGetError handed out; lives until the next call
};
thread_local ThreadError t_error;

std::mutex g_callback_mutex;
OMISErrorFunction g_callback = nullptr;
void* g_callback_user = nullptr;

}  // namespace

void record_error(OMISError code, const char* message) {
    if (t_error.code == OMIS_ERROR_NONE) {  // keep the first error since the last query
        t_error.code = code;
        t_error.message = message;
    }
    OMISErrorFunction callback;
    void* user;
    {
        std::lock_guard<std::mutex> lock(g_callback_mutex);
        callback = g_callback;
        user = g_callback_user;
    }
    if (callback) callback(user, code, message);
}

}  // namespace omis::api

using namespace omis::api;

OMIS_API int omisGetVersion(void) { return OMIS_VERSION; }

OMIS_API OMISError omisGetError(const char** message) {
    const OMISError code = t_error.code;
    t_error.returned = std::move(t_error.message);
    t_error.message.clear();
    t_error.code = OMIS_ERROR_NONE;
    if (message) *message = code == OMIS_ERROR_NONE ? nullptr : t_error.returned.c_str();
    return code;
}

OMIS_API void omisSetErrorFunction(OMISErrorFunction function, void* user) {
    std::lock_guard<std::mutex> lock(g_callback_mutex);
    g_callback = function;
    g_callback_user = user;
}
