#include "models/gp/setup_memo.hpp"

#include <utility>

namespace pp5 {

namespace {

bool same(const SetupMemo::Key& a, const SetupMemo::Key& b) {
  return a.params == b.params && a.expressions == b.expressions && a.words == b.words;
}

}  // namespace

bool SetupMemo::bind(const Key& key, std::size_t primitives) {
  if (bound_ && same(key, key_) && records_.size() == primitives) {
    ++reuses_;
    return true;
  }
  bound_ = true;
  key_ = key;
  records_.assign(primitives, Record{});
  placed_.clear();
  regions_.clear();
  return false;
}

void SetupMemo::begin(int primitive) {
  Record& r = records_[static_cast<std::size_t>(primitive)];
  r.first = static_cast<std::uint32_t>(placed_.size());
  r.count = 0;
}

void SetupMemo::place(std::shared_ptr<const Packet> packet, const std::vector<int>& regions) {
  Placed p;
  p.packet = std::move(packet);
  p.first = static_cast<std::uint32_t>(regions_.size());
  p.count = static_cast<std::uint32_t>(regions.size());
  regions_.insert(regions_.end(), regions.begin(), regions.end());
  placed_.push_back(std::move(p));
}

void SetupMemo::end(int primitive, const PrimitiveTally& tally, const SetupCounts& counts) {
  Record& r = records_[static_cast<std::size_t>(primitive)];
  r.count = static_cast<std::uint32_t>(placed_.size()) - r.first;
  r.tally = tally;
  r.counts = counts;
  r.filled = true;
}

}  // namespace pp5
