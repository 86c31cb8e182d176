// libFuzzer entry point for the config target (see fuzz_targets.hpp).
#include "fuzz/fuzz_targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pp5::fuzz::config(data, size);
  return 0;
}
