#pragma once
// Which Renderer renders which screen region, which GPs send each region packets, and which
// waiting GP goes next: the state the GPs and the Renderers share while bins flow, kept out
// of Machine.
//
// Contract:
//  - Every call names the frame it is about (frames overlap, models/protocol/frame_clock.hpp):
//    a frame's claims and bin senders are kept in slot frame & 1, which the first call of
//    frame n + 2 finds as frame n left it and empties (no unit is on frame n by then); a GP
//    is woken only by a Renderer on the GP's frame.
//  - claim_region(k) gives Renderer k its next region: statically region r to Renderer
//    r mod renderers, in increasing order; dynamically the lowest region nobody has claimed.
//    It returns -1 when there is none, and records the owner.
//  - owner_of_region(r) is -1 until some Renderer has claimed r.
//  - add_bin_senders is called by each GP, once, before its bin map is sent; bin_senders(r)
//    is final once every busy GP's map has reached the Renderer that reads it.
//  - wait_for_input(gp, owed) is where a GP with nothing it can send waits (from its
//    thread): `owed` is the stages (pass * regions + region) it still owes, ascending, and
//    stays as it is while it waits.
//  - input_changed(k, stage) is called by Renderer k whenever it opens a stage for input or
//    frees room in its queue; `stage` is the stage it has open then (-1: none).
//  - Arbitration: one delta after Renderers change, the GPs waiting for a stage that a
//    changed Renderer has open are woken, and only those (a GP can send again only when a
//    stage it owes opens or its queue frees room). They are woken in the order of `order`
//    (gp.send_order): nearest first, by the hops from the GP's ring stop to that Renderer's
//    (set_ring), ties to the lower GP (of messages sent at one instant the one with the
//    fewest hops to go arrives first); lowest-numbered first; or round-robin, beginning with
//    the GP after the one woken last. A GP woken first runs first, and so takes room in a
//    queue first when several want it at one instant. The order is the rule's (an
//    assumption, docs/timing.md "Who goes first"), not the SystemC kernel's order of waking
//    the processes of one event.
#include <memory>
#include <systemc>
#include <vector>

#include "models/config/machine_config.hpp"

namespace pp5 {

class RegionScheduler : public sc_core::sc_module {
 public:
  SC_HAS_PROCESS(RegionScheduler);
  using Order = MachineConfig::Gp::SendOrder;
  RegionScheduler(sc_core::sc_module_name name, int regions, int renderers, int gps, bool dynamic,
                  Order order = Order::nearest);

  // Host side, between frames: no region claimed, no bin sender, no GP waiting, the
  // round-robin turn at GP 0: as a new scheduler, so that every frame starts alike.
  void reset_frame();

  int claim_region(int renderer, int frame = 0);
  int owner_of_region(int region, int frame = 0) const {
    const Slot& s = slot(frame);
    return s.frame == frame ? s.owner[region] : -1;
  }
  void add_bin_senders(const std::vector<int>& regions, int frame = 0);
  int bin_senders(int region, int frame = 0) const {
    const Slot& s = slot(frame);
    return s.frame == frame ? s.bin_senders[region] : 0;
  }
  bool dynamic_balancing() const { return dynamic_; }

  // hops[g][k]: ring hops from GP g's stop to Renderer k's (the arbitration's order).
  void set_ring(std::vector<std::vector<int>> hops) { hops_ = std::move(hops); }
  // `also`, if given, ends the wait too (a GP that may set up its next frame meanwhile), and so
  // does `timeout` elapsing (a GP setting up its next frame: the rest of that set-up).
  void wait_for_input(int gp, const std::vector<int>& owed, int frame = 0,
                      const sc_core::sc_event* also = nullptr,
                      const sc_core::sc_time* timeout = nullptr);
  void input_changed(int renderer, int stage, int frame = 0);
  // frames.gp_send=when_full: GPs send before their bin maps, so a stage no bin map has named
  // yet may still be owed, and its changes wake the GPs that owe it.
  void wake_before_maps(bool on) { wake_before_maps_ = on; }

 private:
  void arbitrate();  // SC_METHOD on changed_

  int regions_;
  int renderers_;
  int gps_;
  bool dynamic_;
  Order order_;
  bool wake_before_maps_ = false;
  struct Slot {
    int frame = 0;                 // the frame it holds
    std::vector<int> owner;        // region -> Renderer, -1 until claimed
    std::vector<int> bin_senders;  // region -> GPs with packets for it
    int next_region = 0;           // dynamic: the next unclaimed region
    std::vector<int> claimed;      // static: regions each Renderer has claimed so far
    void reset(int frame_number);
  };
  Slot slots_[2];
  const Slot& slot(int frame) const { return slots_[frame & 1]; }
  // The slot of `frame`, emptied first if it still holds frame - 2.
  Slot& slot_for(int frame);

  // Renderers changed since the last arbitration, and the stage each has open.
  std::vector<int> changed_;
  std::vector<char> is_changed_;
  std::vector<int> open_stage_;
  std::vector<int> open_frame_;
  sc_core::sc_event changed_event_;
  // Waiting GPs: what each owes (null when it is not waiting) and its wake-up.
  std::vector<const std::vector<int>*> owed_;
  std::vector<int> owed_frame_;
  std::unique_ptr<sc_core::sc_event[]> woken_;
  int waiting_ = 0;
  std::vector<std::vector<int>> hops_;
  std::vector<int> nearest_;  // per GP: its fewest hops to a Renderer that woke it, or -1
  std::vector<int> wake_order_;
  int next_turn_ = 0;  // round_robin: the GP whose turn comes first
};

}  // namespace pp5
