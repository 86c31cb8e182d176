#include "models/gp/setup_memo.hpp"

#include <array>
#include <cstring>
#include <map>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace pp5 {

namespace {

bool same(const SetupMemo::Key& a, const SetupMemo::Key& b) {
  return a.params == b.params && a.expressions == b.expressions && a.words == b.words;
}

// Whether a primitive's set-up counted anything (SetupCounts is all 64-bit counts, with no
// padding: geometry.cpp asserts its size).
bool counted_any(const SetupCounts& c) {
  static const SetupCounts zero{};
  return std::memcmp(&c, &zero, sizeof c) != 0;
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
  counted_.clear();
  filled_ = 0;
  summary_.reset();
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

void SetupMemo::end(int primitive, int kind, const PrimitiveTally& tally,
                    const SetupCounts& counts) {
  Record& r = records_[static_cast<std::size_t>(primitive)];
  r.kind = kind;
  r.count = static_cast<std::uint32_t>(placed_.size()) - r.first;
  r.tally = tally;
  r.counted = kNothingCounted;
  if (counted_any(counts)) {
    r.counted = static_cast<std::uint32_t>(counted_.size());
    counted_.push_back(counts);
  }
  if (!r.filled) ++filled_;
  r.filled = true;
}

void SetupMemo::absorb(SetupMemo&& part, int first, int last) {
  if (part.scene_ != scene_ || !same(part.key_, key_) || part.records_.size() != records_.size())
    throw std::logic_error("SetupMemo::absorb: a part of another scene or key");
  const auto placed_base = static_cast<std::uint32_t>(placed_.size());
  const auto region_base = static_cast<std::uint32_t>(regions_.size());
  const auto counted_base = static_cast<std::uint32_t>(counted_.size());
  for (int i = first; i < last; ++i) {
    Record r = part.records_[static_cast<std::size_t>(i)];
    if (!r.filled) throw std::logic_error("SetupMemo::absorb: a part without a record");
    r.first += placed_base;
    if (r.counted != kNothingCounted) r.counted += counted_base;
    Record& into = records_[static_cast<std::size_t>(i)];
    if (into.filled) throw std::logic_error("SetupMemo::absorb: a record filled twice");
    into = r;
    ++filled_;
  }
  for (Placed& p : part.placed_) {
    p.first += region_base;
    placed_.push_back(std::move(p));
  }
  regions_.insert(regions_.end(), part.regions_.begin(), part.regions_.end());
  counted_.insert(counted_.end(), part.counted_.begin(), part.counted_.end());
  summary_.reset();
}

const SetupMemo::Summary& SetupMemo::summary(int regions) {
  if (!complete()) throw std::logic_error("SetupMemo::summary: a primitive has no record yet");
  if (summary_ && summary_->region_first.size() == static_cast<std::size_t>(regions) + 1)
    return *summary_;
  auto s = std::make_unique<Summary>();
  const std::size_t n = records_.size();
  s->class_of.resize(n);
  // Classes by (kind, pieces, setups, regions); most primitives have their neighbour's.
  std::map<std::array<int, 4>, std::uint32_t> class_index;
  std::array<int, 4> last_key{-1, -1, -1, -1};
  std::uint32_t last_class = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Record& r = records_[i];
    const std::array<int, 4> key{r.kind, r.tally.pieces, r.tally.setups, r.tally.regions};
    if (key != last_key) {
      const auto [it, added] =
          class_index.emplace(key, static_cast<std::uint32_t>(s->classes.size()));
      if (added) s->classes.push_back({r.kind, r.tally});
      last_key = key;
      last_class = it->second;
    }
    s->class_of[i] = last_class;
    if (r.counted != kNothingCounted) s->counted.emplace_back(static_cast<int>(i), counts(r));
  }
  // A checkpoint at every kCheckpoint-th primitive, and one at the end.
  if (s->classes.size() <= Summary::kMaxCheckpointed) {
    std::vector<std::uint32_t> running(s->classes.size(), 0);
    for (std::size_t i = 0; i <= n; ++i) {
      if (i % Summary::kCheckpoint == 0)
        s->checkpoints.insert(s->checkpoints.end(), running.begin(), running.end());
      if (i < n) ++running[s->class_of[i]];
    }
  }
  // Region by region: a count pass, then a fill pass in display-list order.
  s->region_first.assign(static_cast<std::size_t>(regions) + 1, 0);
  for (int region : regions_) ++s->region_first[static_cast<std::size_t>(region) + 1];
  for (int r = 0; r < regions; ++r) s->region_first[r + 1] += s->region_first[r];
  s->region_primitive.resize(regions_.size());
  s->region_packets.resize(regions_.size());
  s->region_words.resize(regions_.size());
  bool uniform = true;
  std::vector<std::uint32_t> next(s->region_first.begin(), s->region_first.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    const Record& r = records_[i];
    for (std::uint32_t p = r.first; p < r.first + r.count; ++p) {
      const Placed& placed = placed_[p];
      for (std::uint32_t q = placed.first; q < placed.first + placed.count; ++q) {
        const std::uint32_t k = next[static_cast<std::size_t>(regions_[q])]++;
        s->region_primitive[k] = static_cast<int>(i);
        s->region_packets[k] = &placed.packet;
        s->region_words[k] = static_cast<std::uint32_t>(placed.packet->words);
        if (s->uniform_words == 0) s->uniform_words = placed.packet->words;
        uniform = uniform && placed.packet->words == s->uniform_words;
      }
    }
  }
  if (!uniform) s->uniform_words = 0;
  s->signature_first.assign(static_cast<std::size_t>(regions) + 1, 0);
  // A region's signatures by (procedure, solid, facing): a map, since a scene of many solids
  // gives a region many.
  std::map<std::tuple<int, int, bool>, std::size_t> in_region;
  for (int r = 0; r < regions; ++r) {
    in_region.clear();
    for (std::uint32_t k = s->region_first[r]; k < s->region_first[r + 1]; ++k) {
      const Packet& p = **s->region_packets[k];
      const auto [it, added] = in_region.emplace(
          std::make_tuple(static_cast<int>(p.procedure), p.group, p.back), s->signatures.size());
      if (added) {
        s->signatures.push_back({&p, 1});
      } else {
        ++s->signatures[it->second].count;
      }
    }
    s->signature_first[static_cast<std::size_t>(r) + 1] =
        static_cast<std::uint32_t>(s->signatures.size());
  }
  summary_ = std::move(s);
  return *summary_;
}

void SetupMemo::Summary::count_classes(int first, int last, std::vector<std::uint32_t>& out) const {
  const std::size_t m = classes.size();
  out.assign(m, 0);
  if (last <= first) return;
  if (checkpoints.empty()) {  // too many classes for checkpoints
    for (int i = first; i < last; ++i) ++out[class_of[static_cast<std::size_t>(i)]];
    return;
  }
  // The counts before `last` minus those before `first`: each from the checkpoint at or
  // below it, then the primitives from the checkpoint on.
  auto add = [&](int at, bool plus) {
    const std::size_t j = static_cast<std::size_t>(at / kCheckpoint);
    for (std::size_t c = 0; c < m; ++c) {
      out[c] = plus ? out[c] + checkpoints[j * m + c] : out[c] - checkpoints[j * m + c];
    }
    for (int i = static_cast<int>(j) * kCheckpoint; i < at; ++i) {
      std::uint32_t& o = out[class_of[static_cast<std::size_t>(i)]];
      o = plus ? o + 1 : o - 1;
    }
  };
  add(last, true);
  add(first, false);
}

}  // namespace pp5
