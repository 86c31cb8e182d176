#include "models/ring/ring.hpp"

namespace pp5 {

Ring::Ring(sc_core::sc_module_name name, const RingParams& params, int stops)
    : sc_module(name),
      params_(params),
      stops_(stops),
      cycle_(1.0 / params.clock_hz, sc_core::SC_SEC),
      free_at_(params.channels, sc_core::SC_ZERO_TIME),
      busy_(params.channels) {}

void Ring::transfer(int from, int to, std::uint64_t words) {
  const sc_core::sc_time now = sc_core::sc_time_stamp();
  int channel = 0;
  for (int c = 1; c < params_.channels; ++c) {
    if (free_at_[c] < free_at_[channel]) channel = c;
  }
  const sc_core::sc_time start = free_at_[channel] > now ? free_at_[channel] : now;
  const sc_core::sc_time length = cycle_ * static_cast<double>(words);
  free_at_[channel] = start + length;
  busy_[channel] += RingCycles(words);
  ++messages_;
  words_ += words;
  const int hops = ((to - from) % stops_ + stops_) % stops_;
  const sc_core::sc_time arrival =
      start + length + cycle_ * static_cast<double>(hops * params_.hop_latency_cycles);
  wait(arrival - now);
}

}  // namespace pp5
