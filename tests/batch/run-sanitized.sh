#!/usr/bin/env bash
# The bad-input corpus and the kill/resume test against an AddressSanitizer + UBSan build
# of uvpress (gcc, -O0: the build is the cost, the corpus runs are small), in a second
# build folder with only the two targets they need (about 6 min of build, 1.5 min of
# tests on 2 cores). Any sanitizer report makes uvpress exit with a code other than 0 or 1, or prints a report
# the tests look for, so the corpus tests fail on it. Leak checking is off: the Vulkan
# loader and OpenImageIO keep process-lifetime allocations that are not bugs.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build=${UVPRESS_ASAN_BUILD:-$root/build-asan}
# -Wno-maybe-uninitialized: gcc 12 with ASan warns inside libstdc++ (std::regex).
flags="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined -Wno-maybe-uninitialized"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-O0 -DNDEBUG" \
  "-DCMAKE_CXX_FLAGS=$flags" "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined" >/dev/null
cmake --build "$build" -j2 --target uvpress uvpress_batch_tests
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=0:exitcode=86
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:exitcode=86
cd "$build"
./tests/uvpress_batch_tests "[corpus],[kill]" --durations yes
