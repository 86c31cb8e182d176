#pragma once
// Host speed only: asks the kernel to back [begin, begin + bytes) with 2 MB pages where whole
// ones fit, so that first touching it takes 1/512 of the page faults (on the development
// machine, a virtual machine, a 4 KB page's first touch costs microseconds). The advice may
// be ignored; nothing depends on it. A no-op off Linux.
#include <cstddef>

namespace pp5 {

void advise_huge_pages(void* begin, std::size_t bytes);

}  // namespace pp5
