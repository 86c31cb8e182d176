#include "firmware/isa/backend.hpp"

#include <vector>

namespace pp5 {

std::int64_t PixelBackend::read_signed(int pixel, const Field& field) const {
  const std::uint64_t v = read(pixel, field);
  if (!field.is_signed || field.width >= 64) return static_cast<std::int64_t>(v);
  const std::uint64_t sign = std::uint64_t{1} << (field.width - 1);
  return static_cast<std::int64_t>((v ^ sign) - sign);
}

void PixelBackend::read_bytes(const Field* fields, int count, std::uint8_t* out) const {
  const auto n = static_cast<std::size_t>(pixels());
  // A region's read-out, every region of every frame: the values' buffer is kept per host
  // thread and reused (read_field writes every value, so it is not cleared). Allocated at
  // each call, its 128 KiB came from fresh pages that the kernel zeroed every time.
  thread_local std::vector<std::uint64_t> values;
  if (values.size() < n) values.resize(n);
  const auto stride = static_cast<std::size_t>(count);
  for (int k = 0; k < count; ++k) {
    read_field(fields[k], values.data());
    for (std::size_t p = 0; p < n; ++p) {
      out[p * stride + static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(values[p]);
    }
  }
}

// Generic: one 1-bit field at a time. A backend that holds bit-planes copies them instead.
void PixelBackend::read_memory_planes(std::vector<std::uint64_t>& planes) const {
  const int n = pixels();
  const int words = (n + 63) / 64;
  const int bits = geometry().memory_bits;
  planes.assign(static_cast<std::size_t>(bits) * words, 0);
  std::vector<std::uint64_t> values(static_cast<std::size_t>(n));
  for (int b = 0; b < bits; ++b) {
    read_field(Field{b, 1, false}, values.data());
    std::uint64_t* plane = &planes[static_cast<std::size_t>(b) * words];
    for (int p = 0; p < n; ++p) plane[p / 64] |= (values[p] & 1) << (p % 64);
  }
}

}  // namespace pp5
