#!/usr/bin/env bash
# The packaged add-on: scripts/package_addon.sh builds a zip that Blender's
# add-on installer accepts; once installed it loads its bundled omis module
# (no PYTHONPATH) and bakes.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
zip="$work/omis_bake.zip"
"$root/scripts/package_addon.sh" --no-build --output "$zip" >/dev/null
mkdir -p "$work/user_scripts"
env -u PYTHONPATH BLENDER_USER_SCRIPTS="$work/user_scripts" OMIS_TEST_ZIP="$zip" \
    "${BLENDER:-blender}" -b --factory-startup --python-exit-code 1 \
    --python "$root/tests/blender/check_package.py"
