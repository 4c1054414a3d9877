#!/usr/bin/env bash
# Installs every Debian package omis needs. Idempotent: apt-get skips what is
# already there, so README commands and CI call it on every run.
set -euo pipefail

packages=(
    build-essential cmake pkg-config
    libembree-dev libtbb-dev
    libopenimageio-dev openimageio-tools python3-imath
    libopencolorio-dev
    pybind11-dev python3-pybind11 python3-dev python3-numpy
    catch2
    python3-pytest python3-matplotlib python3-hypothesis
    python3-distributed
    blender xvfb xauth
)

missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]})); then
    sudo=""
    [[ $(id -u) -ne 0 ]] && sudo="sudo"
    echo "omis: installing ${missing[*]}"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
