#include "models/pixel_array/backends.hpp"

#include <stdexcept>

#include "models/pixel_array/bit_sliced_backend.hpp"
#include "models/pixel_array/word_backend.hpp"

namespace pp5 {

const std::vector<PixelBackendInfo>& pixel_backends() {
  static const std::vector<PixelBackendInfo> backends = {
      {"bit",
       "bit-serial on bit-sliced pixel memory, as the hardware: every instruction walks its "
       "operands one bit-plane per array cycle",
       [](const PixelBackendParams& p) -> std::unique_ptr<PixelBackend> {
         return std::make_unique<BitSlicedBackend>(p);
       }},
      {"word", "one host integer per field and pixel, executed a whole field at a time (wide SIMD)",
       [](const PixelBackendParams& p) -> std::unique_ptr<PixelBackend> {
         return std::make_unique<WordBackend>(p);
       }},
  };
  return backends;
}

const PixelBackendInfo* find_pixel_backend(const std::string& name) {
  for (const PixelBackendInfo& b : pixel_backends()) {
    if (name == b.name) return &b;
  }
  return nullptr;
}

std::unique_ptr<PixelBackend> make_pixel_backend(const std::string& name,
                                                 const PixelBackendParams& params) {
  if (const PixelBackendInfo* b = find_pixel_backend(name)) return b->make(params);
  std::string known;
  for (const PixelBackendInfo& b : pixel_backends()) {
    known += known.empty() ? "" : ", ";
    known += b.name;
  }
  throw std::invalid_argument("unknown pixel backend '" + name + "' (known: " + known + ")");
}

}  // namespace pp5
