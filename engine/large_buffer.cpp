// Storage for UninitializedAllocator (engine.h): large buffers in 2 MiB pages.
//
// Eval's reference views (up to ~230 MB), its render chunks and the candidates' renders are
// written once, front to back, right after they are allocated. In 4 KiB pages each of them
// is ~50,000 page faults, and in a virtual machine a fault costs microseconds: Fox's
// reference views took 2.0 s to render into fresh 4 KiB pages here, 1.2 s into huge pages
// and 0.6 s into memory already mapped. Asked for huge pages (madvise;
// Linux's transparent huge pages in their default "madvise" mode), the kernel maps 2 MiB
// a fault. Where the kernel has none or refuses, the buffer is an ordinary one.
#include "engine.h"

#include <cstdlib>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace uvpress::engine {

namespace {
constexpr size_t kHugePage = size_t(2) << 20;
constexpr size_t kLarge = size_t(8) << 20;  // below this, malloc's own pages serve as well
size_t rounded(size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }
}  // namespace

void* allocate_buffer(size_t bytes) {
  if (bytes < kLarge) {
    void* p = std::malloc(bytes ? bytes : 1);
    if (!p) throw std::bad_alloc();
    return p;
  }
  void* p = std::aligned_alloc(kHugePage, rounded(bytes));
  if (!p) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  madvise(p, rounded(bytes), MADV_HUGEPAGE);  // advice only: its failure changes nothing
#endif
  return p;
}

void free_buffer(void* p) { std::free(p); }

}  // namespace uvpress::engine
