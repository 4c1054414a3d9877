#!/usr/bin/env bash
# Regenerates the pictures of README.md and docs/ (after scripts/build.sh):
#   docs/images/panel.png           the add-on's panel under Cycles, as Blender draws it
#                                   (tests/blender/test_panel_screenshot.py on a virtual
#                                   X server; needs the Debian package xvfb)
#   docs/images/demo_vs_cycles.png  the demo floor baked by omis and by Cycles in the same
#                                   wall time (scripts/docs_demo_vs_cycles.py; with .txt)
# The race plot, bench/results/cycles_vs_omis.png, comes from bench/bench_cycles.py
# (see docs/benchmarks.md). Extra arguments reach docs_demo_vs_cycles.py.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
shots="$(mktemp -d)"
trap 'rm -rf "$shots"' EXIT
OMIS_SCREENSHOT_DIR="$shots" bash scripts/blender_run.sh --ui tests/blender/test_panel_screenshot.py
mkdir -p docs/images
cp "$shots/panel_cycles.png" docs/images/panel.png
bash scripts/blender_run.sh scripts/docs_demo_vs_cycles.py "$@"
ls -l docs/images
