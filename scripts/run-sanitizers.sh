#!/usr/bin/env bash
# CI, after the README test command: the core and C ABI tests built with
# AddressSanitizer + UndefinedBehaviorSanitizer in a second build directory
# (${OMIS_SANITIZE_BUILD_DIR:-build-sanitize}). Any finding fails the run.
# Only what those tests need is built (no Python module, no benchmarks).
# Embree and TBB come from Debian uninstrumented: their own memory is not
# checked, calls into them are.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${OMIS_SANITIZE_BUILD_DIR:-$root/build-sanitize}"

"$root/scripts/install-deps.sh"
sanitize="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DPython3_EXECUTABLE=/usr/bin/python3 -DOMIS_BUILD_BENCH=OFF \
    -DCMAKE_C_FLAGS="$sanitize" -DCMAKE_CXX_FLAGS="$sanitize" \
    -DCMAKE_EXE_LINKER_FLAGS="$sanitize" -DCMAKE_SHARED_LINKER_FLAGS="$sanitize" >/dev/null

# Set before building: catch_discover_tests runs the core test binary to list it.
export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export LSAN_OPTIONS="suppressions=$root/scripts/sanitizers.supp:print_suppressions=0"

cmake --build "$build" -j"$(nproc)" --target omis_core_tests omis_capi_estimator_tests \
    omis_capi_scene_tests omis_capi_lighting_tests omis_capi_bake_tests omis_capi_receiver_tests \
    omis_capi_inputs_tests omis_capi_bake_convergence_tests omis_capi_snapshot_tests \
    omis_capi_world_image_tests \
    omis_bake_floor
cd "$build"
ctest --output-on-failure -j"$(nproc)" -L '^(core|capi)$'
