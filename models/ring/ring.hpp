#pragma once
// The ring network: stops in a loop (GPs, Renderers, frame buffer), `channels` parallel
// channels of `word_bits` each, one word per channel per ring cycle.
//
// Contract (the simple model; contention is per channel, hops pipeline): a message takes
// the channel that frees first, holds it for one ring cycle per word, and arrives
// `hops * hop_latency_cycles` after its last word leaves. transfer() blocks the calling
// SystemC thread until arrival. Channel choice breaks ties by the lowest index, so runs
// are deterministic.
#include <cstdint>
#include <systemc>
#include <vector>

#include "models/common/units.hpp"

namespace pp5 {

struct RingParams {
  int channels = 8;
  int word_bits = 32;
  double clock_hz = 20e6;
  int hop_latency_cycles = 1;
};

class Ring : public sc_core::sc_module {
 public:
  Ring(sc_core::sc_module_name name, const RingParams& params, int stops);

  void transfer(int from, int to, std::uint64_t words);

  const RingParams& params() const { return params_; }
  std::uint64_t messages() const { return messages_; }
  std::uint64_t words() const { return words_; }
  // Ring cycles each channel spent carrying words.
  const std::vector<RingCycles>& busy() const { return busy_; }
  double bandwidth_bits_per_second() const {
    return params_.channels * params_.word_bits * params_.clock_hz;
  }

 private:
  RingParams params_;
  int stops_;
  sc_core::sc_time cycle_;
  std::vector<sc_core::sc_time> free_at_;
  std::vector<RingCycles> busy_;
  std::uint64_t messages_ = 0;
  std::uint64_t words_ = 0;
};

}  // namespace pp5
