#pragma once
// splitmix64: a small generator whose sequence is fixed by its seed on every host and every
// standard library (std::mt19937's distributions are not), for seeded samples whose results
// are compared across machines: the analytic level's validation grids, validate's joint
// sensitivity sample.
#include <cstdint>
#include <vector>

namespace pp5 {

struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, n) (n > 0; the modulo's bias is below 2^-32 for the small n used here).
  int below(int n) { return static_cast<int>(next() % static_cast<std::uint64_t>(n)); }
  // Uniform in [0, 1), 53 random bits.
  double unit() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  template <class T>
  const T& pick(const std::vector<T>& v) {
    return v[static_cast<std::size_t>(below(static_cast<int>(v.size())))];
  }
};

}  // namespace pp5
