#!/usr/bin/env bash
# The bad-input corpus and the kill/resume test against an AddressSanitizer + UBSan build
# of uvpress (gcc, -O0), in a second build folder with only the two targets they need.
# The build is a unity build (CMake joins each target's sources into a few files: half the
# compiler time, since every file parses the same heavy headers; it also refuses two files
# that define the same internal name) with Ninja where it is installed (it compiles across
# targets at once); the tests run as two processes, the kill/resume case beside the corpus.
# Measured on 2 cores: build 368 s (make, a file at a time) -> 181 s; tests 522 s -> 301 s
# (two processes; and uvpress now starts once, not twice: the malformed-asset case 340 -> 193 s).
# -O1 builds for 5 min and saves no test time. Any sanitizer report makes uvpress exit
# with a code other than 0 or 1, or prints a report the tests look for, so the corpus
# tests fail on it. Leak checking is off: the Vulkan loader keeps process-lifetime
# allocations that are not bugs.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build=${UVPRESS_ASAN_BUILD:-$root/build-asan}
# -Wno-maybe-uninitialized: gcc 12 with ASan warns inside libstdc++ (std::regex).
flags="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined -Wno-maybe-uninitialized"
generator=()
# A folder configured before keeps its generator (CMake refuses to switch).
if [ ! -f "$build/CMakeCache.txt" ] && command -v ninja >/dev/null; then generator=(-G Ninja); fi
cmake "${generator[@]}" -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-O0 -DNDEBUG" \
  "-DCMAKE_CXX_FLAGS=$flags" "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined" -DCMAKE_UNITY_BUILD=ON >/dev/null
cmake --build "$build" -j2 --target uvpress uvpress_batch_tests
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=0:exitcode=86
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:exitcode=86
cd "$build"
# The kill/resume case beside the [corpus] cases, in parallel (each about half the time:
# 300 s and 285 s side by side here); both logs printed when both have ended.
./tests/uvpress_batch_tests "[kill]" --durations yes >sanitized-1.log 2>&1 &
first=$!
status=0
./tests/uvpress_batch_tests "[corpus]" --durations yes >sanitized-2.log 2>&1 || status=$?
wait "$first" || status=$?
cat sanitized-1.log sanitized-2.log
exit "$status"
