// engine::UninitializedVector (engine.h, engine/large_buffer.cpp): the renders' and GMSD's
// storage. It must behave as a std::vector in everything but zeroing: contents kept when
// it grows and moves, large buffers on 2 MiB boundaries (the huge-page path), small ones
// from malloc.
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
  CHECK(reinterpret_cast<uintptr_t>(v.data()) % alignof(float) == 0);
  // 3 M floats (12 MB) then 9 M: a large buffer, reallocated once more.
  v.resize(size_t(3) << 20);
  for (size_t i = 1000; i < v.size(); ++i) v[i] = float(i);
  CHECK(reinterpret_cast<uintptr_t>(v.data()) % (size_t(2) << 20) == 0);
  v.resize(size_t(9) << 20);
  CHECK(reinterpret_cast<uintptr_t>(v.data()) % (size_t(2) << 20) == 0);
  bool kept = true;
  for (size_t i = 0; i < (size_t(3) << 20); ++i) kept = kept && v[i] == float(i);
  CHECK(kept);
  // Shrinking keeps the storage; a copy is an independent equal vector.
  const float* storage = v.data();
  v.resize(10);
  CHECK(v.data() == storage);
  UninitializedVector<float> copy = v;
  CHECK(copy == v);
  copy[3] = -1.0f;
  CHECK(v[3] == 3.0f);
  UninitializedVector<uint32_t> none;
  none.shrink_to_fit();
  CHECK(none.empty());
}
