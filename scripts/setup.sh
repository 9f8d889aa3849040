#!/usr/bin/env bash
# Installs what caustics needs on a Debian/Ubuntu machine, skipping what is
# already there: the Vulkan loader, Mesa's lavapipe (CPU Vulkan, used when
# there is no GPU), the Khronos validation layer, shaderc/glslang/SPIRV-Tools
# static libraries (build.rs compiles GLSL with them), Xvfb for the windowed
# demo's headless test. Needs root or sudo for apt-get. Rust itself (cargo,
# 1.85 or newer) must already be installed, e.g. with rustup.
set -euo pipefail

packages=(
  libvulkan1 mesa-vulkan-drivers vulkan-validationlayers
  libshaderc-dev glslang-dev spirv-tools
  g++ pkg-config xvfb xauth
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}" >&2
  sudo=""
  if [ "$(id -u)" != 0 ]; then sudo="sudo"; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if ! command -v cargo >/dev/null 2>&1; then
  echo "setup: cargo not found; install Rust 1.85 or newer (https://rustup.rs) and run again" >&2
  exit 1
fi
