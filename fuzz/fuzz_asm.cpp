// libFuzzer entry point for the asm target (see fuzz_targets.hpp).
#include "fuzz/fuzz_targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pp5::fuzz::assembler(data, size);
  return 0;
}
