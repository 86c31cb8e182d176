#pragma once
// Which Renderer renders which screen region, and which GPs send each region packets: the
// state the GPs and the Renderers share while bins flow, kept out of Machine.
//
// Contract:
//  - claim_region(k) gives Renderer k its next region: statically region r to Renderer
//    r mod renderers, in increasing order; dynamically the lowest region nobody has claimed.
//    It returns -1 when there is none, and records the owner.
//  - owner_of_region(r) is -1 until some Renderer has claimed r.
//  - add_bin_senders is called by each GP, once, before its bin map is sent; bin_senders(r)
//    is final once every busy GP's map has reached the Renderer that reads it.
//  - input_changed() is notified whenever a Renderer opens a stage for input or frees room in
//    its queue: what a GP with nothing to send waits for.
#include <systemc>
#include <vector>

namespace pp5 {

class RegionScheduler {
 public:
  RegionScheduler(int regions, int renderers, bool dynamic);

  int claim_region(int renderer);
  int owner_of_region(int region) const { return owner_[region]; }
  void add_bin_senders(const std::vector<int>& regions);
  int bin_senders(int region) const { return bin_senders_[region]; }
  bool dynamic_balancing() const { return dynamic_; }
  sc_core::sc_event& input_changed() { return input_changed_; }

 private:
  int regions_;
  int renderers_;
  bool dynamic_;
  std::vector<int> owner_;        // region -> Renderer, -1 until claimed
  std::vector<int> bin_senders_;  // region -> GPs with packets for it
  int next_region_ = 0;           // dynamic: the next unclaimed region
  std::vector<int> claimed_;      // static: regions each Renderer has claimed so far
  sc_core::sc_event input_changed_;
};

}  // namespace pp5
