#!/usr/bin/env bash
# README command (b): check function lengths, install, configure, build, and run
# every test through ctest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${OMIS_BUILD_DIR:-$root/build}"
# No function over 100 lines (fails before the build, in a second).
python3 "$root/scripts/long_functions.py" --check "$root/core"
"$root/scripts/build.sh"
cd "$build"
ctest --output-on-failure -j"$(nproc)"
