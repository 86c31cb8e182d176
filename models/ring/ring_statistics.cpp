// The statistics of the ring (see common/statistics.hpp for the registry's contract).
#include <string>

#include "common/statistics.hpp"
#include "models/ring/ring.hpp"

namespace pp5 {

void Ring::register_statistics(Statistics& stats, double frame_seconds) const {
  namespace u = stat_unit;
  stats.add_integer("ring.messages", u::count, "Messages carried (bin maps, bins, regions)",
                    [this] { return static_cast<std::int64_t>(messages_); });
  stats.add_integer("ring.words", u::ring_words, "Words carried, over all channels",
                    [this] { return static_cast<std::int64_t>(words_); });
  stats.add_real("ring.bandwidth_bits_per_second", u::bits_per_second,
                 "Capacity: channels x word_bits x clock",
                 [this] { return bandwidth_bits_per_second(); });
  stats.add_real("ring.utilisation", u::ratio,
                 "words as a fraction of what all channels could carry in the frame time",
                 [this, frame_seconds] {
                   const double capacity = params_.channels * params_.clock_hz * frame_seconds;
                   return capacity > 0 ? static_cast<double>(words_) / capacity : 0;
                 });
  stats.add_integer("ring.contention_cycles", u::ring_cycles,
                    "Cycles messages waited for a free channel, summed",
                    [this] { return static_cast<std::int64_t>(contention_.count); });
  for (std::size_t k = 0; k < busy_.size(); ++k) {
    const std::string p = "ring.channels." + std::to_string(k) + ".";
    stats.add_integer(p + "busy_cycles", u::ring_cycles, "Cycles the channel carried words",
                      [this, k] { return static_cast<std::int64_t>(busy_[k].count); });
    stats.add_real(
        p + "utilisation", u::ratio, "busy_cycles as a fraction of the frame time",
        [this, k, frame_seconds] { return busy_[k].seconds(params_.clock_hz) / frame_seconds; });
  }
}

}  // namespace pp5
