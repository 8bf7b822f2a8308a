#!/usr/bin/env bash
# Installs everything uvpress needs to build, test and run its demo on Debian bookworm:
# Debian packages through apt-get (gnuplot-nox draws eval's plot; chromium lets the eval
# HTML test load the report headless; slurmctld, slurmd and munge run the batch test's
# one-node cluster on loopback; clang and libclang-rt-14-dev build the libFuzzer targets;
# libdeflate-dev deflates PNG rows tighter than zlib (zlib1g-dev inflates them);
# libastcenc-dev is the ASTC codec of --texture-format astc and eval --codec, and the
# astcenc command decodes the KTX2 files in the tests), and, from npm into
# tools/node_modules (project-local, never global, exact versions in tools/package.json):
# the Khronos glTF validator, three.js (tests/client renders inputs and outputs with its
# GLTFLoader in headless Chromium) and ktx-parse (the tests read uvpress's KTX2 files with
# it, tools/ktx2-inspect.mjs). Idempotent: when everything is
# present it only checks and returns.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

packages=(
  build-essential cmake ninja-build pkg-config git ca-certificates
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools glslang-tools spirv-tools
  libeigen3-dev libsuitesparse-dev libopenblas-dev
  libtinygltf-dev nlohmann-json3-dev libstb-dev
  libopenimageio-dev openimageio-tools libpng-dev zlib1g-dev libjpeg62-turbo-dev libimagequant-dev libdeflate-dev
  libastcenc-dev astcenc
  catch2 libcli11-dev libnlopt-cxx-dev
  gnuplot-nox chromium
  slurmctld slurmd slurm-client munge
  clang libclang-rt-14-dev
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Node.js and npm: any working node >= 18 with npm will do (some images ship NodeSource's,
# which bundles npm and conflicts with Debian's npm package).
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  missing+=(nodejs npm)
fi

sudo=""
[ "$(id -u)" = 0 ] || sudo="sudo"
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Khronos glTF validator (a library; tools/validate-gltf.mjs drives it), three.js (the
# real-client check, tests/client) and ktx-parse (tools/ktx2-inspect.mjs). Reinstalled when
# one is missing or three's version is not the pinned one.
three_pinned="$(sed -n 's/.*"three": *"\([^"]*\)".*/\1/p' "$here/package.json")"
three_have=""
if [ -f "$here/node_modules/three/package.json" ]; then
  three_have="$(sed -n 's/^ *"version": *"\([^"]*\)".*/\1/p' "$here/node_modules/three/package.json" | head -1)"
fi
if [ ! -f "$here/node_modules/gltf-validator/package.json" ] || [ ! -f "$here/node_modules/ktx-parse/package.json" ] ||
  [ "$three_have" != "$three_pinned" ]; then
  echo "install-deps: installing gltf-validator, three and ktx-parse from npm into tools/node_modules" >&2
  (cd "$here" && npm install --no-audit --no-fund --silent >/dev/null)
fi
echo "install-deps: ok" >&2
