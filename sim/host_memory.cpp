#include "sim/host_memory.hpp"

#include <malloc.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "common/huge_pages.hpp"

namespace pp5 {
namespace {
// The heap's head below its first huge page (tune_host_memory); volatile, so that the
// allocation is made although nothing reads it.
void* volatile heap_head = nullptr;
}  // namespace

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
  if (to <= from) return;
  advise_huge_pages(reinterpret_cast<void*>(from), to - from);
  // The heap's start is wherever address-space randomisation put it: up to 2 MB below the
  // first huge page, whose 4 KB pages would each fault on first touch (SystemC's static
  // initialisers alone zero 3 MB). That head is taken by an allocation that is never used
  // (or touched, beyond its header), so that the allocations that follow start in the huge
  // pages.
  constexpr std::size_t kHeader = 2 * sizeof(std::size_t);  // glibc's chunk header
  if (from - lo > 2 * kHeader) {
    heap_head = std::malloc(from - lo - 2 * kHeader);
  }
}

}  // namespace pp5
