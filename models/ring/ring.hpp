#pragma once
// The ring network: stops in a loop (GPs, Renderers, frame buffer), `channels` parallel
// channels of `word_bits` each, one word per channel per ring cycle. GP-to-Renderer bins and
// Renderer-to-frame-buffer regions share the channels.
//
// Contract (contention is per channel, hops pipeline): a message takes the channel that
// frees first (ties to the lowest index, so runs are deterministic), holds it for one ring
// cycle per word from max(now, channel free), and arrives `hops * hop_latency_cycles` after
// its last word leaves. No channel ever carries more than one word per cycle, so the ring
// never exceeds channels x word_bits x clock. reserve() books a message and returns when it
// arrives without blocking; transfer() blocks the calling SystemC thread until arrival.
//
// Units talk through the ring: a unit that receives messages attaches a RingEndpoint at its
// stop, and send_bin, send_bin_map and send_region book a message (as reserve does) and hand
// it, at booking time, to the endpoint of the stop it is addressed to, with its arrival time;
// the receiver must not act on it before then. A message to a stop with no endpoint, or of a
// kind its endpoint does not take, is a wiring error (std::logic_error).
#include <cstdint>
#include <memory>
#include <string>
#include <systemc>
#include <vector>

#include "common/units.hpp"
#include "models/protocol/packet.hpp"

namespace pp5 {

class Statistics;

struct RingParams {
  int channels = 8;
  int word_bits = 32;
  double clock_hz = 20e6;
  int hop_latency_cycles = 1;
};

// Hops from stop `from` to stop `to` on a ring of `stops`, in the direction words travel.
inline int ring_hops(int from, int to, int stops) { return ((to - from) % stops + stops) % stops; }
// The latency of those hops: one ring cycle (`cycle`, 1 / clock_hz) per hop and latency cycle.
inline sc_core::sc_time ring_hop_delay(const RingParams& params, sc_core::sc_time cycle, int from,
                                       int to, int stops) {
  return cycle * static_cast<double>(ring_hops(from, to, stops) * params.hop_latency_cycles);
}

// One message on the ring, for the timeline.
struct RingMessage {
  int channel = 0;
  int from = 0;
  int to = 0;
  std::uint64_t words = 0;
  sc_core::sc_time start;    // first word leaves
  sc_core::sc_time end;      // last word leaves: the channel is free again
  sc_core::sc_time arrival;  // last word reaches `to`
};

struct RingBooking {
  sc_core::sc_time end;      // the sender's interface is free again
  sc_core::sc_time arrival;  // the message has fully arrived
};

// Part of a GP's bin for one (region, pass), as one ring message into a Renderer's queue.
struct BinMessage {
  int region = 0;
  int pass = 0;
  int gp = 0;
  bool last = false;  // the GP's final message for this (region, pass)
  std::vector<std::shared_ptr<const Packet>> packets;
  std::uint64_t words = 0;
  sc_core::sc_time requested;  // the GP asked the ring for it
  sc_core::sc_time arrival;    // fully in the Renderer's queue
};

// A GP's bin map as one Renderer receives it (the regions are in the RegionScheduler).
struct BinMapArrival {
  int gp = 0;
  int frame = 0;               // the frame whose bins it maps (frames overlap)
  sc_core::sc_time requested;  // the GP asked the ring for it
  sc_core::sc_time arrival;    // fully at this stop
};

// A finished region's colours, from a Renderer to the frame buffer.
struct RegionArrival {
  int region = 0;
  sc_core::sc_time arrival;
};

// A message of the GPs' depth sort (models/gp/depth_sort.hpp DepthSortWork), GP to GP.
struct SortArrival {
  enum class Kind { run, order, records };
  Kind kind = Kind::run;
  int from_gp = 0;
  int frame = 0;
  std::uint64_t words = 0;
  sc_core::sc_time arrival;  // fully at this stop
};

// What a unit at a ring stop receives. Each kind of message has its own entry; a unit
// overrides those it takes, and the others refuse the message (std::logic_error).
class RingEndpoint {
 public:
  virtual ~RingEndpoint() = default;
  // Part of a bin; message->arrival is when it is fully in the receiver's queue.
  virtual void receive_bin(std::shared_ptr<const BinMessage> message);
  virtual void receive_bin_map(const BinMapArrival& map);
  virtual void receive_region(const RegionArrival& region);
  virtual void receive_sort(const SortArrival& message);
};

class Ring : public sc_core::sc_module {
 public:
  Ring(sc_core::sc_module_name name, const RingParams& params, int stops);

  // `not_before`: the sender's interface is busy until then (default: now).
  RingBooking reserve(int from, int to, std::uint64_t words,
                      sc_core::sc_time not_before = sc_core::SC_ZERO_TIME);
  void transfer(int from, int to, std::uint64_t words);

  // `endpoint` receives the messages addressed to `stop` (not owned; it must outlive the
  // ring's use).
  void attach(int stop, RingEndpoint& endpoint);
  // Books `message` (message->words) from `from` to `to`, sets its arrival and hands it to
  // `to`'s endpoint.
  RingBooking send_bin(int from, int to, std::shared_ptr<BinMessage> message);
  // Books one bin map of `words` from `from` past every stop of `to` (booked to the farthest:
  // the nearer ones see it on the way) and hands each its arrival, in the order of `to`.
  RingBooking send_bin_map(int from, const std::vector<int>& to, std::uint64_t words, int gp,
                           int frame = 0);
  // Books a depth-sort message of `message.words` from `from` past every stop of `to` (one
  // stop, or several: booked to the farthest, as a bin map) and hands each its arrival.
  RingBooking send_sort(int from, const std::vector<int>& to, SortArrival message);
  // Books a finished region from `from` to `to`, starting no earlier than `not_before`, and
  // hands it to `to`'s endpoint.
  RingBooking send_region(int from, int to, std::uint64_t words, int region,
                          sc_core::sc_time not_before = sc_core::SC_ZERO_TIME);
  // Time from a message's last word leaving `from` to its arrival at `to`: a message booked
  // to the farthest of several stops passes the nearer ones on the way (a broadcast).
  sc_core::sc_time hop_delay(int from, int to) const;
  int hops(int from, int to) const { return ring_hops(from, to, stops_); }

  // Host side, between frames: a new frame begins at `start`, after every booking so far
  // ended; each channel is free from then on, as in a new ring (so the next message takes
  // channel 0), and the counts start again from 0. The message log is kept, for a timeline
  // over all frames.
  void reset_frame(sc_core::sc_time start);

  // Keep every message for the timeline (off by default: it costs memory).
  void record_messages(bool on) { record_ = on; }
  const std::vector<RingMessage>& messages_log() const { return log_; }
  // Drops the messages kept so far (a run that writes its timeline out frame by frame).
  void clear_messages_log() { log_.clear(); }

  const RingParams& params() const { return params_; }
  int stops() const { return stops_; }
  std::uint64_t messages() const { return messages_; }
  std::uint64_t words() const { return words_; }
  // Ring cycles each channel spent carrying words.
  const std::vector<RingCycles>& busy() const { return busy_; }
  // Cycles messages waited for a free channel, summed.
  RingCycles contention() const { return contention_; }
  double bandwidth_bits_per_second() const {
    return params_.channels * params_.word_bits * params_.clock_hz;
  }
  // Registers ring.* (models/ring/ring_statistics.cpp); read once the frame has run.
  void register_statistics(Statistics& stats, double frame_seconds) const;

 private:
  RingParams params_;
  int stops_;
  sc_core::sc_time cycle_;
  std::vector<sc_core::sc_time> free_at_;
  std::vector<RingCycles> busy_;
  RingCycles contention_{};
  std::uint64_t messages_ = 0;
  std::uint64_t words_ = 0;
  RingEndpoint& endpoint(int stop) const;

  bool record_ = false;
  std::vector<RingMessage> log_;
  std::vector<RingEndpoint*> endpoints_;  // by stop, null where nothing receives
};

}  // namespace pp5
