#include "models/ring/ring.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace pp5 {

Ring::Ring(sc_core::sc_module_name name, const RingParams& params, int stops)
    : sc_module(name),
      params_(params),
      stops_(stops),
      cycle_(1.0 / params.clock_hz, sc_core::SC_SEC),
      free_at_(params.channels, sc_core::SC_ZERO_TIME),
      busy_(params.channels),
      endpoints_(static_cast<std::size_t>(stops), nullptr) {}

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

void Ring::reset_frame(sc_core::sc_time start) {
  std::fill(free_at_.begin(), free_at_.end(), start);
  std::fill(busy_.begin(), busy_.end(), RingCycles{});
  contention_ = RingCycles{};
  messages_ = 0;
  words_ = 0;
}

sc_core::sc_time Ring::hop_delay(int from, int to) const {
  return ring_hop_delay(params_, cycle_, from, to, stops_);
}

void Ring::transfer(int from, int to, std::uint64_t words) {
  const RingBooking b = reserve(from, to, words);
  wait(b.arrival - sc_core::sc_time_stamp());
}

void RingEndpoint::receive_bin(std::shared_ptr<const BinMessage>) {
  throw std::logic_error("ring: a bin message reached a stop that takes none");
}

void RingEndpoint::receive_bin_map(const BinMapArrival&) {
  throw std::logic_error("ring: a bin map reached a stop that takes none");
}

void RingEndpoint::receive_region(const RegionArrival&) {
  throw std::logic_error("ring: a finished region reached a stop that takes none");
}

void RingEndpoint::receive_sort(const SortArrival&) {
  throw std::logic_error("ring: a depth-sort message reached a stop that takes none");
}

void Ring::attach(int stop, RingEndpoint& endpoint) {
  endpoints_.at(static_cast<std::size_t>(stop)) = &endpoint;
}

RingEndpoint& Ring::endpoint(int stop) const {
  RingEndpoint* e = endpoints_.at(static_cast<std::size_t>(stop));
  if (e == nullptr) {
    throw std::logic_error("ring: a message to stop " + std::to_string(stop) +
                           ", where nothing is attached");
  }
  return *e;
}

RingBooking Ring::send_bin(int from, int to, std::shared_ptr<BinMessage> message) {
  RingEndpoint& receiver = endpoint(to);
  const RingBooking b = reserve(from, to, message->words);
  message->arrival = b.arrival;
  receiver.receive_bin(std::move(message));
  return b;
}

RingBooking Ring::send_bin_map(int from, const std::vector<int>& to, std::uint64_t words, int gp,
                               int frame) {
  int farthest = to.at(0);
  for (int stop : to) {
    if (hops(from, stop) > hops(from, farthest)) farthest = stop;
  }
  const sc_core::sc_time requested = sc_core::sc_time_stamp();
  const RingBooking b = reserve(from, farthest, words);
  for (int stop : to) {
    endpoint(stop).receive_bin_map({gp, frame, requested, b.end + hop_delay(from, stop)});
  }
  return b;
}

RingBooking Ring::send_sort(int from, const std::vector<int>& to, SortArrival message) {
  int farthest = to.at(0);
  for (int stop : to) {
    if (hops(from, stop) > hops(from, farthest)) farthest = stop;
  }
  const RingBooking b = reserve(from, farthest, message.words);
  for (int stop : to) {
    message.arrival = b.end + hop_delay(from, stop);
    endpoint(stop).receive_sort(message);
  }
  return b;
}

RingBooking Ring::send_region(int from, int to, std::uint64_t words, int region,
                              sc_core::sc_time not_before) {
  RingEndpoint& receiver = endpoint(to);
  const RingBooking b = reserve(from, to, words, not_before);
  receiver.receive_region({region, b.arrival});
  return b;
}

}  // namespace pp5
