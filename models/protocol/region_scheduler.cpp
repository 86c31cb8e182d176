#include "models/protocol/region_scheduler.hpp"

#include <algorithm>

namespace pp5 {

RegionScheduler::RegionScheduler(sc_core::sc_module_name name, int regions, int renderers, int gps,
                                 bool dynamic, Order order)
    : sc_module(name),
      regions_(regions),
      renderers_(renderers),
      gps_(gps),
      dynamic_(dynamic),
      order_(order),
      owner_(regions, -1),
      bin_senders_(regions, 0),
      claimed_(renderers, 0),
      is_changed_(renderers, 0),
      open_stage_(renderers, -1),
      owed_(gps, nullptr),
      woken_(new sc_core::sc_event[gps > 0 ? gps : 1]),
      hops_(gps, std::vector<int>(renderers, 0)),
      nearest_(gps, -1) {
  changed_.reserve(renderers);
  wake_order_.reserve(gps);
  SC_METHOD(arbitrate);
  sensitive << changed_event_;
  dont_initialize();
}

void RegionScheduler::reset_frame() {
  std::fill(owner_.begin(), owner_.end(), -1);
  std::fill(bin_senders_.begin(), bin_senders_.end(), 0);
  next_region_ = 0;
  std::fill(claimed_.begin(), claimed_.end(), 0);
  changed_.clear();
  std::fill(is_changed_.begin(), is_changed_.end(), 0);
  std::fill(open_stage_.begin(), open_stage_.end(), -1);
  std::fill(owed_.begin(), owed_.end(), nullptr);
  waiting_ = 0;
  std::fill(nearest_.begin(), nearest_.end(), -1);
  wake_order_.clear();
  next_turn_ = 0;
}

int RegionScheduler::claim_region(int renderer) {
  int region = -1;
  if (dynamic_) {
    if (next_region_ < regions_) region = next_region_++;
  } else {
    const int r = renderer + claimed_[renderer] * renderers_;
    if (r < regions_) {
      region = r;
      ++claimed_[renderer];
    }
  }
  if (region >= 0) owner_[region] = renderer;
  return region;
}

void RegionScheduler::add_bin_senders(const std::vector<int>& regions) {
  for (int r : regions) ++bin_senders_[r];
}

void RegionScheduler::wait_for_input(int gp, const std::vector<int>& owed) {
  owed_[gp] = &owed;
  ++waiting_;
  sc_core::wait(woken_[gp]);
}

void RegionScheduler::input_changed(int renderer, int stage) {
  open_stage_[renderer] = stage;
  // A stage no GP has packets for wakes nobody: on a large screen most stages are empty.
  // Room freed in a queue matters only to the GPs owing its open stage, which are senders.
  if (stage < 0 || bin_senders_[stage % regions_] == 0 || is_changed_[renderer]) return;
  is_changed_[renderer] = 1;
  changed_.push_back(renderer);
  changed_event_.notify(sc_core::SC_ZERO_TIME);
}

void RegionScheduler::arbitrate() {
  wake_order_.clear();
  for (const int k : changed_) {
    is_changed_[k] = 0;
    const int s = open_stage_[k];  // its latest: the stage it has open now
    if (s < 0 || waiting_ == 0) continue;
    for (int g = 0; g < gps_; ++g) {
      const std::vector<int>* owed = owed_[g];
      if (owed == nullptr || !std::binary_search(owed->begin(), owed->end(), s)) continue;
      const int hops = hops_[g][k];
      if (nearest_[g] < 0) wake_order_.push_back(g);
      if (nearest_[g] < 0 || hops < nearest_[g]) nearest_[g] = hops;
    }
  }
  changed_.clear();
  switch (order_) {
    case Order::nearest:
      std::sort(wake_order_.begin(), wake_order_.end(), [this](int a, int b) {
        return nearest_[a] != nearest_[b] ? nearest_[a] < nearest_[b] : a < b;
      });
      break;
    case Order::lowest:
      std::sort(wake_order_.begin(), wake_order_.end());
      break;
    case Order::round_robin: {
      // Each GP's place in the turn: the GP at next_turn_ first, then the ones after it.
      const auto place = [this](int g) { return (g - next_turn_ + gps_) % gps_; };
      std::sort(wake_order_.begin(), wake_order_.end(),
                [&place](int a, int b) { return place(a) < place(b); });
      if (!wake_order_.empty()) next_turn_ = (wake_order_.back() + 1) % gps_;
      break;
    }
  }
  for (const int g : wake_order_) {
    nearest_[g] = -1;
    owed_[g] = nullptr;
    --waiting_;
    woken_[g].notify();  // immediate: the GPs run in the order they are woken
  }
}

}  // namespace pp5
