#include "sim/host_memory.hpp"

#include <malloc.h>
#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>

namespace pp5 {

void tune_host_memory() {
  mallopt(M_MMAP_THRESHOLD, 256 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
  constexpr std::size_t kHeap = std::size_t{64} << 20;
  constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
  void* grown = std::malloc(kHeap);
  if (grown == nullptr) return;
  const auto lo = reinterpret_cast<std::uintptr_t>(grown);
  const std::uintptr_t from = (lo + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t to = (lo + kHeap) & ~(kHuge - 1);
  std::free(grown);  // stays in the heap (below the trim threshold) for what comes next
  if (to > from) madvise(reinterpret_cast<void*>(from), to - from, MADV_HUGEPAGE);
}

}  // namespace pp5
