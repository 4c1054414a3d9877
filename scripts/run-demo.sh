#!/usr/bin/env bash
# README command (a): the main job inside headless Blender. Builds omis (and
# installs Blender), then scripts/blender_demo.py builds the demo room with bpy
# and bakes its floor with the omis_bake add-on, with the balance heuristic and
# with optimal MIS at equal time; writes EXR/PNG results, a noise comparison and
# a table to out/demo/. Extra arguments (--seconds S, --size N, --out DIR) reach
# the script. The same bake without Blender: scripts/demo_bake.py.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/build.sh"
cd "$root"
exec bash scripts/blender_run.sh scripts/blender_demo.py --out out/demo "$@"
