#!/usr/bin/env bash
# README command (a): the main job on the built-in default scene. Bakes the
# demo room's floor with the balance heuristic and with optimal MIS at equal
# time; writes EXR/PNG results, a noise comparison and a table to out/demo/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${OMIS_BUILD_DIR:-$root/build}"
"$root/scripts/build.sh"
cd "$root"
PYTHONPATH="$build/python" /usr/bin/python3 scripts/demo_bake.py --out out/demo "$@"
