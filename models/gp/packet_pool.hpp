#pragma once
// A GP's packet memory, kept across the frames of a run: one frame's packets come from one
// arena (blocks of packets made once and reused, coefficient storage and all), and every
// packet of that arena is handed out as a std::shared_ptr<const Packet> that shares the
// arena's one count (the aliasing constructor), not an allocation and a count per packet.
// An arena goes back to its pool when the last of its packets is dropped, on whatever
// thread drops it (bins, ring messages, a Renderer's regions, a helper thread's pixel work,
// a set-up memo), and a later frame takes it again.
//
// Contract:
//  - PacketPool::take() gives an arena with no packet handed out; the pool outlives every
//    arena it gave (each holds the pool's state), so a pool may go before its packets do.
//  - PacketArena::make() gives a packet with every field at its default (a Packet{}, with
//    the coefficient storage of the packet that slot last held kept for reuse); the
//    packet lives, and is not handed out again, while any shared_ptr to it or to another
//    packet of the same take() lives.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "models/protocol/packet.hpp"

namespace pp5 {

class PacketArena {
 public:
  // A default packet at a slot no live packet uses; `owner` is the arena's own pointer (as
  // take() gave it), which the packet's pointer shares.
  std::shared_ptr<Packet> make(const std::shared_ptr<PacketArena>& owner) {
    if (used_ == blocks_.size() * kBlock) blocks_.push_back(std::make_unique<Packet[]>(kBlock));
    Packet& p = blocks_[used_ / kBlock][used_ % kBlock];
    ++used_;
    CarriedExpressions kept = std::move(p.values.expressions);
    kept.clear();
    p = Packet{};
    p.values.expressions = std::move(kept);
    return std::shared_ptr<Packet>(owner, &p);
  }
  std::size_t size() const { return used_; }  // packets handed out since take()
  std::size_t capacity() const { return blocks_.size() * kBlock; }

 private:
  friend class PacketPool;
  static constexpr std::size_t kBlock = 256;
  std::vector<std::unique_ptr<Packet[]>> blocks_;
  std::size_t used_ = 0;
};

class PacketPool {
 public:
  PacketPool() : state_(std::make_shared<State>()) {}

  std::shared_ptr<PacketArena> take() {
    std::unique_ptr<PacketArena> arena, stale;
    {
      const std::lock_guard<std::mutex> lock(state_->mutex);
      ++state_->takes;
      if (!state_->free.empty()) {  // the one back last
        arena = std::move(state_->free.back().arena);
        state_->free.pop_back();
      }
      // One idle since long ago is no longer needed (more were in flight once than are now):
      // it goes, outside the lock.
      if (!state_->free.empty() && state_->free.front().back_at + kStale < state_->takes) {
        stale = std::move(state_->free.front().arena);
        state_->free.erase(state_->free.begin());
      }
    }
    if (!arena) arena = std::make_unique<PacketArena>();
    arena->used_ = 0;
    return std::shared_ptr<PacketArena>(arena.release(), GiveBack{state_});
  }
  // Arenas waiting in the pool (for tests).
  std::size_t idle() const {
    const std::lock_guard<std::mutex> lock(state_->mutex);
    return state_->free.size();
  }

 private:
  // A run's memory follows the frames in flight lately, not the most there ever were: at most
  // two arenas wait (a bin buffer's frame may still be held by the ring, the Renderers and a
  // helper thread two frames on), and one that has waited kStale takes is freed.
  static constexpr std::size_t kIdle = 2;
  static constexpr std::uint64_t kStale = 8;
  struct Idle {
    std::unique_ptr<PacketArena> arena;
    std::uint64_t back_at = 0;  // `takes` when it came back
  };
  struct State {
    mutable std::mutex mutex;
    std::vector<Idle> free;  // oldest first
    std::uint64_t takes = 0;
  };
  struct GiveBack {
    std::shared_ptr<State> state;
    void operator()(PacketArena* arena) const {
      std::unique_ptr<PacketArena> a(arena);
      const std::lock_guard<std::mutex> lock(state->mutex);
      // Beyond kIdle, freed (outside the lock).
      if (state->free.size() < kIdle) state->free.push_back({std::move(a), state->takes});
    }
  };
  std::shared_ptr<State> state_;
};

}  // namespace pp5
