#!/usr/bin/env bash
# Installs the Debian 12 packages prism builds with, if any is missing. Needs root (or sudo).
set -euo pipefail
packages=(build-essential cmake pkg-config libglm-dev libtinyexr-dev libstb-dev nlohmann-json3-dev
          libpugixml-dev libtbb-dev doctest-dev libbenchmark-dev)
if [[ "${1:-}" == "--with-embree" ]]; then packages+=(libembree-dev); fi
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  sudo=""; [[ $(id -u) -ne 0 ]] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
