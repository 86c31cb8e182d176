// libFuzzer entry point for the CSG expression target (see fuzz_targets.hpp).
#include "fuzz/fuzz_targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pp5::fuzz::csg(data, size);
  return 0;
}
