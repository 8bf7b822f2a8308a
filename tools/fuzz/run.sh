#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan) and runs each for its share of
# TOTAL seconds (default 60): fuzz_gltf (glTF/GLB through load_gltf and build_asset),
# fuzz_mesh (OBJ/OFF), fuzz_image (PNG/JPEG/... through io/image_decode.h). Seeds: tools/fuzz/seeds,
# small generated PNG/JPEG, and ../shared/assets when present. Exits non-zero on the first
# crash, leaving the input in BUILD/artifacts. Prints one line per target with its runs.
set -euo pipefail
total=${1:-60}
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build=${UVPRESS_FUZZ_BUILD:-$root/build-fuzz}
CXX=clang++ cmake -S "$root/tools/fuzz" -B "$build" >/dev/null
cmake --build "$build" -j2 >/dev/null

corpus="$build/corpus"
mkdir -p "$corpus/gltf" "$corpus/mesh" "$corpus/image" "$build/artifacts"
cp "$root"/tools/fuzz/seeds/*.gltf "$corpus/gltf/"
cp "$root"/tools/fuzz/seeds/*.obj "$root"/tools/fuzz/seeds/*.off "$corpus/mesh/"
if command -v oiiotool >/dev/null; then
  oiiotool --pattern checker:width=4:height=4 16x16 3 -d uint8 -o "$corpus/image/checker.png" >/dev/null 2>&1 || true
  oiiotool --pattern fill:top=0,0,0:bottom=1,1,1 8x8 4 -d uint16 -o "$corpus/image/ramp16.png" >/dev/null 2>&1 || true
  oiiotool --pattern checker 16x16 3 -d uint8 -o "$corpus/image/checker.jpg" >/dev/null 2>&1 || true
fi
shared="$root/../shared/assets"
if [ -d "$shared" ]; then
  # The glTF target's first byte picks the format (odd: .glb, even: .gltf).
  find "$shared" -name '*.glb' -size -400k | head -n 4 | while read -r f; do
    { printf '\001'; cat "$f"; } > "$corpus/gltf/$(basename "$f").seed"; done
  find "$shared" -name '*.gltf' -size -100k | head -n 4 | while read -r f; do
    { printf '\000'; cat "$f"; } > "$corpus/gltf/$(basename "$f").seed"; done
  find "$shared" -name '*.png' -size -100k | head -n 4 | while read -r f; do cp "$f" "$corpus/image/"; done
  find "$shared" -name '*.obj' -size -200k | head -n 2 | while read -r f; do { printf 'v'; cat "$f"; } > "$corpus/mesh/$(basename "$f").seed"; done
fi

# A fixed seed and a fixed number of runs per target (capped by the time share) make the
# CI step deterministic: what passed here passes there; a longer local run finds more.
declare -A runs_of=([gltf]=${UVPRESS_FUZZ_RUNS_GLTF:-30000} [mesh]=${UVPRESS_FUZZ_RUNS_MESH:-200000} [image]=${UVPRESS_FUZZ_RUNS_IMAGE:-8000})
each=$(( total / 3 ))
[ "$each" -ge 1 ] || each=1
status=0
for target in gltf mesh image; do
  log="$build/fuzz_$target.log"
  if ASAN_OPTIONS=detect_leaks=0:allocator_may_return_null=1 "$build/fuzz_$target" "$corpus/$target" \
      -max_total_time="$each" -runs="${runs_of[$target]}" -seed=1 -print_final_stats=1 -rss_limit_mb=3072 -malloc_limit_mb=2048 -timeout=20 \
      -artifact_prefix="$build/artifacts/$target-" >"$log" 2>&1; then
    runs=$(grep -m1 'stat::number_of_executed_units' "$log" | awk '{print $2}')
    echo "fuzz_$target: ${runs:-?} runs in ${each} s, no crash"
  else
    echo "fuzz_$target: CRASH (see $log and $build/artifacts)" >&2
    tail -n 40 "$log" >&2
    status=1
  fi
done
exit $status
