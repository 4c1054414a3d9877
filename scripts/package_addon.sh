#!/usr/bin/env bash
# Builds the installable Blender add-on zip: blender_addon/omis_bake/ plus the
# compiled omis module for this platform, bundled as omis_bake/omis/:
#
#   omis_bake/                 the add-on (bl_info, panel, operator, exporter)
#   omis_bake/omis/            the omis package: *.py, _omis.cpython-311-*.so,
#                              libomis.so.0 (found through the extension's $ORIGIN rpath)
#
#   scripts/package_addon.sh [--no-build] [--output PATH]
#
# Output: ${OMIS_BUILD_DIR:-build}/omis_bake.zip unless --output is given.
# Install: Blender ▸ Edit ▸ Preferences ▸ Add-ons ▸ Install… ▸ the zip, then tick
# "Render: omis Bake (Optimal MIS)". The zip needs the same Debian libraries the
# build used (Embree 3, oneTBB, OpenImageIO, OpenColorIO: scripts/install-deps.sh).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${OMIS_BUILD_DIR:-$root/build}"
output=""
do_build=1
while [[ $# -gt 0 ]]; do
    case "$1" in
        --no-build) do_build=0; shift ;;
        --output) output="$2"; shift 2 ;;
        *) echo "usage: $0 [--no-build] [--output PATH]" >&2; exit 2 ;;
    esac
done
output="${output:-$build/omis_bake.zip}"

if [[ $do_build -eq 1 ]]; then
    if [[ ! -f "$build/CMakeCache.txt" ]]; then
        "$root/scripts/install-deps.sh"
        cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release \
            -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
    fi
    cmake --build "$build" --target omis_python -j"$(nproc)"
fi

module="$build/python/omis"
shopt -s nullglob
extension=("$module"/_omis*.so)
library=("$build"/lib/libomis.so.0)
if [[ ${#extension[@]} -ne 1 || ${#library[@]} -ne 1 ]]; then
    echo "$0: no built omis module in $build (expected python/omis/_omis*.so and lib/libomis.so.0)" >&2
    exit 1
fi

stage="$(mktemp -d)"
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/omis_bake/omis"
cp "$root"/blender_addon/omis_bake/*.py "$stage/omis_bake/"
cp "$module"/*.py "${extension[0]}" "$stage/omis_bake/omis/"
cp -L "${library[0]}" "$stage/omis_bake/omis/libomis.so.0"
mkdir -p "$(dirname "$output")"
rm -f "$output"
(cd "$stage" && /usr/bin/python3 -m zipfile -c "$output.tmp" omis_bake)
mv "$output.tmp" "$output"
echo "$output"
