#!/usr/bin/env bash
# README command (a): the main job on the built-in default scene.
# Until baking exists: the estimator demo on the built-in 1-D problems.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${OMIS_BUILD_DIR:-$root/build}"
"$root/scripts/build.sh"
"$build/bench/omis_bench_mis" --table
