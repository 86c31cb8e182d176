#pragma once
// Clock-domain-safe cycle counts. Pixel-Planes 5 has three clocks (the 40 MHz array, the
// 40 MHz i860 and the ring); mixing them is the classic bug, so each has its own type and
// only an explicit conversion through a frequency turns one into seconds.
#include <cstdint>

namespace pp5 {

template <class Clock>
struct Cycles {
  std::uint64_t count = 0;

  constexpr Cycles() = default;
  constexpr explicit Cycles(std::uint64_t n) : count(n) {}
  constexpr Cycles operator+(Cycles o) const { return Cycles(count + o.count); }
  constexpr Cycles& operator+=(Cycles o) {
    count += o.count;
    return *this;
  }
  constexpr Cycles operator*(std::uint64_t k) const { return Cycles(count * k); }
  constexpr bool operator==(Cycles o) const { return count == o.count; }
  constexpr bool operator!=(Cycles o) const { return count != o.count; }
  constexpr bool operator<(Cycles o) const { return count < o.count; }
  double seconds(double clock_hz) const { return static_cast<double>(count) / clock_hz; }
};

struct ArrayClock {};
struct GpClock {};
struct RingClock {};
using ArrayCycles = Cycles<ArrayClock>;  // Renderer micro-instruction cycles
using GpClocks = Cycles<GpClock>;        // i860 clocks
using RingCycles = Cycles<RingClock>;    // ring word times

}  // namespace pp5
