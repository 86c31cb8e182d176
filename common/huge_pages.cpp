#include "common/huge_pages.hpp"

#include <cstdint>
#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace pp5 {

void advise_huge_pages(void* begin, std::size_t bytes) {
#if defined(__linux__)
  constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;
  const auto lo = reinterpret_cast<std::uintptr_t>(begin);
  const std::uintptr_t first = (lo + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t last = (lo + bytes) & ~(kHugePage - 1);
  if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#else
  (void)begin;
  (void)bytes;
#endif
}

}  // namespace pp5
