// engine::UninitializedVector (engine.h, engine/large_buffer.cpp): the renders' and GMSD's
// storage. Its own allocate/deallocate must keep a std::vector's contract: contents kept
// when it grows into a new buffer, large buffers from the huge-page path (2 MiB aligned).
#include <catch2/catch.hpp>

#include "engine.h"

#include <cstdint>
#include <numeric>

using namespace uvpress::engine;

TEST_CASE("engine buffers: an UninitializedVector keeps its contents through growth, large ones page-aligned",
          "[engine]") {
  UninitializedVector<float> v;
  v.resize(1000);
  std::iota(v.begin(), v.end(), 0.0f);
  // 3 M floats (12 MB) then 9 M: a large buffer, reallocated once more.
  v.resize(size_t(3) << 20);
  for (size_t i = 1000; i < v.size(); ++i) v[i] = float(i);
  CHECK(reinterpret_cast<uintptr_t>(v.data()) % (size_t(2) << 20) == 0);
  v.resize(size_t(9) << 20);
  CHECK(reinterpret_cast<uintptr_t>(v.data()) % (size_t(2) << 20) == 0);
  bool kept = true;
  for (size_t i = 0; i < (size_t(3) << 20); ++i) kept = kept && v[i] == float(i);
  CHECK(kept);
  // A copy of a large buffer is allocated by the same path and holds the same values.
  const UninitializedVector<float> copy = v;
  CHECK(reinterpret_cast<uintptr_t>(copy.data()) % (size_t(2) << 20) == 0);
  CHECK(copy == v);
}
