#include "models/renderer/region_scheduler.hpp"

namespace pp5 {

RegionScheduler::RegionScheduler(int regions, int renderers, bool dynamic)
    : regions_(regions),
      renderers_(renderers),
      dynamic_(dynamic),
      owner_(regions, -1),
      bin_senders_(regions, 0),
      claimed_(renderers, 0) {}

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

}  // namespace pp5
