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
      is_changed_(renderers, 0),
      open_stage_(renderers, -1),
      open_frame_(renderers, 0),
      owed_(gps, nullptr),
      owed_frame_(gps, 0),
      woken_(new sc_core::sc_event[gps > 0 ? gps : 1]),
      hops_(gps, std::vector<int>(renderers, 0)),
      nearest_(gps, -1) {
  for (Slot& s : slots_) {
    s.owner.assign(static_cast<std::size_t>(regions), -1);
    s.bin_senders.assign(static_cast<std::size_t>(regions), 0);
    s.claimed.assign(static_cast<std::size_t>(renderers), 0);
  }
  slots_[1].frame = 1;
  changed_.reserve(renderers);
  wake_order_.reserve(gps);
  SC_METHOD(arbitrate);
  sensitive << changed_event_;
  dont_initialize();
}

void RegionScheduler::Slot::reset(int frame_number) {
  frame = frame_number;
  std::fill(owner.begin(), owner.end(), -1);
  std::fill(bin_senders.begin(), bin_senders.end(), 0);
  next_region = 0;
  std::fill(claimed.begin(), claimed.end(), 0);
}

RegionScheduler::Slot& RegionScheduler::slot_for(int frame) {
  Slot& s = slots_[frame & 1];
  if (s.frame != frame) s.reset(frame);
  return s;
}

void RegionScheduler::reset_frame() {
  for (Slot& s : slots_) {
    s.owner.assign(static_cast<std::size_t>(regions_), -1);
    s.bin_senders.assign(static_cast<std::size_t>(regions_), 0);
    s.claimed.assign(static_cast<std::size_t>(renderers_), 0);
  }
  slots_[0].reset(0);
  slots_[1].reset(1);
  std::fill(open_frame_.begin(), open_frame_.end(), 0);
  std::fill(owed_frame_.begin(), owed_frame_.end(), 0);
  changed_.clear();
  std::fill(is_changed_.begin(), is_changed_.end(), 0);
  std::fill(open_stage_.begin(), open_stage_.end(), -1);
  std::fill(owed_.begin(), owed_.end(), nullptr);
  waiting_ = 0;
  std::fill(nearest_.begin(), nearest_.end(), -1);
  wake_order_.clear();
  next_turn_ = 0;
}

int RegionScheduler::claim_region(int renderer, int frame) {
  Slot& s = slot_for(frame);
  int region = -1;
  if (dynamic_) {
    if (s.next_region < regions_) region = s.next_region++;
  } else {
    const int r = renderer + s.claimed[renderer] * renderers_;
    if (r < regions_) {
      region = r;
      ++s.claimed[renderer];
    }
  }
  if (region >= 0) s.owner[region] = renderer;
  return region;
}

void RegionScheduler::add_bin_senders(const std::vector<int>& regions, int frame) {
  Slot& s = slot_for(frame);
  for (int r : regions) ++s.bin_senders[r];
}

void RegionScheduler::wait_for_input(int gp, const std::vector<int>& owed, int frame,
                                     const sc_core::sc_event* also,
                                     const sc_core::sc_time* timeout) {
  owed_[gp] = &owed;
  owed_frame_[gp] = frame;
  ++waiting_;
  if (also == nullptr && timeout == nullptr) {
    sc_core::wait(woken_[gp]);
    return;
  }
  if (timeout != nullptr && also != nullptr) {
    sc_core::wait(*timeout, woken_[gp] | *also);
  } else if (timeout != nullptr) {
    sc_core::wait(*timeout, woken_[gp]);
  } else {
    sc_core::wait(woken_[gp] | *also);
  }
  if (owed_[gp] != nullptr) {  // ended by `also`: no longer waiting for a stage
    owed_[gp] = nullptr;
    nearest_[gp] = -1;
    --waiting_;
  }
}

void RegionScheduler::input_changed(int renderer, int stage, int frame) {
  open_stage_[renderer] = stage;
  open_frame_[renderer] = frame;
  // A stage no GP has packets for wakes nobody: on a large screen most stages are empty.
  // Room freed in a queue matters only to the GPs owing its open stage, which are senders.
  if (stage < 0 || is_changed_[renderer] ||
      (!wake_before_maps_ && bin_senders(stage % regions_, frame) == 0))
    return;
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
      if (owed == nullptr || owed_frame_[g] != open_frame_[k] ||
          !std::binary_search(owed->begin(), owed->end(), s))
        continue;
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
