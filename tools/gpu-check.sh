#!/bin/bash
# The device check of a lent GPU machine (the device tool's `run`), from the repository root
# there, with the bundle that tools/gpu-bundle.sh made here carried (carry [".gpu"]), and the
# Debian packages the machine lacks downloaded beside it once (see docs/DEVELOPERS.md, "On a
# real GPU"). Runs the [vulkan] test cases on the GPU with the validation layer on, then the
# benchmarks that have a GPU line; writes logs and JSON lines under $OUT. Each step has its
# own time limit so that one slow step leaves the others their time: about 4 minutes in all.
set -u
cd "$(dirname "$0")/.."
G=$PWD/.gpu
OUT=${OUT:-/tmp/gpu-check}
mkdir -p "$OUT"
tar -xJf "$G/lib.tar.xz" -C "$G"
# The Vulkan loader and glvnd go to / (the NVIDIA ICD, libGLX_nvidia, needs them where
# ldconfig finds them); the validation layer stays in /tmp.
for f in "$G"/gl/*.deb; do dpkg -x "$f" /; done
ldconfig
mkdir -p /tmp/vk
for f in "$G"/debs/*.deb; do dpkg -x "$f" /tmp/vk; done
mkdir -p build/tools && ln -sf "$G/bin/uvpress" build/tools/uvpress  # for the CLI test cases
export LD_LIBRARY_PATH=$G/lib:/tmp/vk/usr/lib/x86_64-linux-gnu
export VK_LAYER_PATH=/tmp/vk/usr/share/vulkan/explicit_layer.d
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f "$icd" ] && export VK_DRIVER_FILES=$icd VK_ICD_FILENAMES=$icd
nvidia-smi -L
B=$G/bin/uvpress
A=$G/assets
step() {
  local limit=$1
  shift
  echo "== $* ($(date +%T))"
  timeout "$limit" "$@"
  echo "rc=$? ($(date +%T))"
}
cd /tmp
UVPRESS_TEST_VULKAN=gpu step 90 "$G/bin/uvpress_tests" "[vulkan]" >"$OUT/tests.log" 2>&1
tail -3 "$OUT/tests.log"
step 45 "$B" bench views --batch 1000 --batch 10000 --batch 50000 | tee "$OUT/views.jsonl"
step 45 "$B" bench views --asset "$A/Fox/glTF/Fox.gltf" --batch 10000 | tee "$OUT/views-fox.jsonl"
UVPRESS_VALIDATION=1 step 30 "$B" --device gpu bench views --batch 1000 2>&1 | tail -3
step 90 "$B" bench triangles --asset demo --asset "$A/Fox/glTF/Fox.gltf" --triangles 256 | tee "$OUT/triangles.jsonl"
step 30 "$B" bench luminance | tee "$OUT/luminance.jsonl"
step 30 "$B" bench rebake | tee "$OUT/rebake.jsonl"
step 40 "$B" --device gpu bench eval --asset "$A/Duck/glTF-Binary/Duck.glb" | tee "$OUT/eval.jsonl"
step 60 "$B" --device gpu bench quality --only --asset "$A/Duck/glTF-Binary/Duck.glb" 2>"$OUT/quality.err" |
  tee "$OUT/quality.jsonl"
