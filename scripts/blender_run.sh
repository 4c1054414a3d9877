#!/usr/bin/env bash
# Runs a Python script in headless Blender with the omis_bake add-on enabled
# from the source tree (blender_addon/) and the omis module from the build
# (${OMIS_BUILD_DIR:-build}/python). Arguments after the script reach it as
# sys.argv[sys.argv.index("--") + 1:].
#
#   scripts/blender_run.sh [--blend FILE.blend] [--ui] [--screen WxH] SCRIPT.py [ARGS...]
#
# --blend opens a .blend file first. --ui starts Blender with its interface on
# a virtual X server (xvfb-run, Debian package xvfb) with event simulation, for
# scripts that drive the interactive (modal) path; such a script ends Blender
# itself. --screen sets that server's size (default 1280x800; Blender's default
# layout scales with it). Exits non-zero when the script raises (Blender's --python-exit-code).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${OMIS_BUILD_DIR:-$root/build}"
blend=()
ui=0
screen=1280x800
while [[ $# -gt 0 ]]; do
    case "$1" in
        --blend) blend=("$2"); shift 2 ;;
        --ui) ui=1; shift ;;
        --screen) screen="$2"; shift 2 ;;
        *) break ;;
    esac
done
if [[ $# -lt 1 ]]; then
    echo "usage: $0 [--blend FILE.blend] [--ui] [--screen WxH] SCRIPT.py [ARGS...]" >&2
    exit 2
fi
script="$1"
shift
if [[ ! -d "$build/python/omis" ]]; then
    echo "$0: no omis module in $build/python (run scripts/build.sh, or set OMIS_BUILD_DIR)" >&2
    exit 2
fi
export PYTHONPATH="$build/python${PYTHONPATH:+:$PYTHONPATH}"
export OMIS_ADDON_DIR="$root/blender_addon"
blender="${BLENDER:-blender}"
enable=(--python "$root/scripts/blender_enable_addon.py")
if [[ $ui -eq 1 ]]; then
    exec xvfb-run -a -s "-screen 0 ${screen}x24" "$blender" "${blend[@]}" --factory-startup \
        --enable-event-simulate --python-exit-code 1 "${enable[@]}" --python "$script" -- "$@"
fi
exec "$blender" -b "${blend[@]}" --factory-startup --python-exit-code 1 \
    "${enable[@]}" --python "$script" -- "$@"
