#!/usr/bin/env bash
# Installs the Debian packages the project needs, when they are missing.
# Idempotent: a package already installed is left alone, and nothing runs apt
# when everything is present. Usage: scripts/install-deps.sh [run|test]
#   run  : what the main job needs (Vulkan loader + lavapipe, OpenXR loader,
#          the GLSL compiler used by runtime/build.rs)
#   test : the above, plus the Khronos validation layer and Xvfb for the tests
set -euo pipefail

want=(
  libvulkan1            # Vulkan loader
  mesa-vulkan-drivers   # lavapipe: a CPU Vulkan device, so no GPU is needed
  glslang-tools         # glslangValidator: compiles shaders/*.glsl to SPIR-V at build time
  libopenxr-loader1     # OpenXR loader (runtime xr); absent runtimes are reported, not fatal
  pkg-config
  libxkbcommon-x11-0 libx11-xcb1 libxcursor1 libxrandr2 libxi6  # loaded at run time by winit's X11 backend (runtime mirror)
)
if [ "${1:-run}" = "test" ]; then
  want+=(
    vulkan-validationlayers  # VK_LAYER_KHRONOS_validation for the validation-clean tests
    xvfb                     # a virtual X server for the mirror-window tests
    xauth
    jq                       # scripts/check-msrv.sh reads `cargo metadata`
  )
fi

missing=()
for p in "${want[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all system packages present (${want[*]})"
  exit 0
fi

echo "install-deps: installing missing Debian packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO=sudo; else
    echo "install-deps: need root (or sudo) to install: ${missing[*]}" >&2; exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "install-deps: done"
