#pragma once
// A GP's packets binned by screen region, each bin in display-list order, holding only the
// regions the GP has packets for: on a 4096 x 4096 screen a share of the display list
// touches a few of 1,024 regions, and what a GP keeps and walks per frame follows those
// regions, not the screen.
//
// Contract:
//  - reset(regions) empties it for a screen of `regions` regions.
//  - add(r, p) appends p to region r's bin.
//  - finish() orders the bins by region; after it, regions() lists the regions with a
//    packet in ascending order, slot(r) is r's index in regions() (-1 for a region without
//    one) and bin(r) its packets (empty for a region without one). add() after finish()
//    needs another finish().
//  - make_packet() gives a default packet from the bins' packet memory (models/gp/
//    packet_pool.hpp): one arena per reset(), reused once every packet made since that
//    reset() has been dropped, wherever it went.
#include <algorithm>
#include <cstddef>
#include <memory>
#include <numeric>
#include <vector>

#include "models/gp/packet_pool.hpp"
#include "models/protocol/packet.hpp"

namespace pp5 {

class RegionBins {
 public:
  using Bin = std::vector<std::shared_ptr<const Packet>>;

  explicit RegionBins(int regions = 0) { reset(regions); }

  // The bins emptied keep their storage for the next frame's packets (a GP's bin buffers
  // persist across the frames of a run).
  void reset(int regions) {
    slot_.assign(static_cast<std::size_t>(regions), -1);
    for (std::size_t k = 0; k < regions_.size(); ++k) bins_[k].clear();
    regions_.clear();
    arena_.reset();  // this frame's packets may go back to the pool before the next take
    arena_ = pool_.take();
  }

  std::shared_ptr<Packet> make_packet() { return arena_->make(arena_); }

  void add(int region, std::shared_ptr<const Packet> packet) {
    int& s = slot_[static_cast<std::size_t>(region)];
    if (s < 0) {
      s = static_cast<int>(regions_.size());
      if (regions_.size() == bins_.size()) bins_.emplace_back();
      regions_.push_back(region);
    }
    bins_[static_cast<std::size_t>(s)].push_back(std::move(packet));
  }

  void finish() {
    if (std::is_sorted(regions_.begin(), regions_.end())) return;
    const std::size_t n = regions_.size();
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(),
              [this](std::size_t a, std::size_t b) { return regions_[a] < regions_[b]; });
    std::vector<int> regions(n);
    std::vector<Bin> bins(n);
    for (std::size_t k = 0; k < n; ++k) {
      regions[k] = regions_[order[k]];
      bins[k] = std::move(bins_[order[k]]);
      slot_[static_cast<std::size_t>(regions[k])] = static_cast<int>(k);
    }
    regions_ = std::move(regions);
    for (std::size_t k = 0; k < n; ++k) bins_[k] = std::move(bins[k]);
  }

  const std::vector<int>& regions() const { return regions_; }
  int slot(int region) const { return slot_[static_cast<std::size_t>(region)]; }
  const Bin& bin(int region) const {
    const int s = slot(region);
    return s < 0 ? empty_ : bins_[static_cast<std::size_t>(s)];
  }

 private:
  std::vector<int> slot_;     // region -> index in regions_ and bins_, -1 for none
  std::vector<int> regions_;  // regions with a packet
  std::vector<Bin> bins_;     // the first regions_.size() in use, the rest empty, kept
  Bin empty_;
  PacketPool pool_;
  std::shared_ptr<PacketArena> arena_;
};

}  // namespace pp5
