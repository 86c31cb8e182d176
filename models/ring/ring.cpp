#include "models/ring/ring.hpp"

#include <algorithm>
#include <cmath>

namespace pp5 {

Ring::Ring(sc_core::sc_module_name name, const RingParams& params, int stops)
    : sc_module(name),
      params_(params),
      stops_(stops),
      cycle_(1.0 / params.clock_hz, sc_core::SC_SEC),
      free_at_(params.channels, sc_core::SC_ZERO_TIME),
      busy_(params.channels) {}

RingBooking Ring::reserve(int from, int to, std::uint64_t words, sc_core::sc_time not_before) {
  const sc_core::sc_time now = std::max(sc_core::sc_time_stamp(), not_before);
  int channel = 0;
  for (int c = 1; c < params_.channels; ++c) {
    if (free_at_[c] < free_at_[channel]) channel = c;
  }
  const sc_core::sc_time start = free_at_[channel] > now ? free_at_[channel] : now;
  if (start > now)
    contention_ += RingCycles(static_cast<std::uint64_t>(std::llround((start - now) / cycle_)));
  const sc_core::sc_time length = cycle_ * static_cast<double>(words);
  free_at_[channel] = start + length;
  busy_[channel] += RingCycles(words);
  ++messages_;
  words_ += words;
  RingBooking b;
  b.end = start + length;
  b.arrival = b.end + hop_delay(from, to);
  if (record_) log_.push_back({channel, from, to, words, start, b.end, b.arrival});
  return b;
}

sc_core::sc_time Ring::hop_delay(int from, int to) const {
  return cycle_ * static_cast<double>(hops(from, to) * params_.hop_latency_cycles);
}

void Ring::transfer(int from, int to, std::uint64_t words) {
  const RingBooking b = reserve(from, to, words);
  wait(b.arrival - sc_core::sc_time_stamp());
}

}  // namespace pp5
