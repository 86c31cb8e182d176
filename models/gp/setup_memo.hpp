#pragma once
// The GPs' set-up of one scene, kept from frame to frame: for runs of many configurations of
// the same scene (pp5sim sweep, pp5sim validate), which would otherwise transform, light, clip
// and set up every primitive again at every point.
//
// What geometry_pass makes of a display-list primitive (its pieces, the set-up counts, its
// packets and the regions each goes to) depends only on the scene, the geometry parameters
// (screen, regions, subpixel, fraction, depth and coefficient bits, culling, frame
// parameters) and, for each primitive kind, the expressions its procedure uses and its
// packet's ring words. Those are the key. A frame whose key matches the memo's replays each
// primitive's record; one whose key differs empties the memo and fills it again. What
// depends on the GP configuration, the i860 operations and clocks, is counted at every
// frame from the record's tally, as for a primitive set up afresh.
//
// Contract:
//  - A frame with the memo gives the same packets (shared, immutable), bins, set-up counts,
//    operations and clocks as one without it: statistics and images are identical
//    (tests/test_setup_memo.cpp).
//  - One frame at a time: Machine::use_setup_memo binds it, and geometry_pass fills it; GPs
//    run one after another (SystemC threads, or the analytic model's loop).
//  - It serves one scene, the one it was made for; a Machine of another scene is refused.
//    The scene is known by its address, so it must not change while the memo serves it
//    (sweep and validate hold theirs const).
//  - summary() sums the records up for a model that needs counts, not packets (the analytic
//    timing model, models/renderer/analytic.hpp); it needs every primitive's record
//    (complete()) and lasts until the key changes.
#include <cstdint>
#include <memory>
#include <vector>

#include "models/gp/geometry.hpp"
#include "models/gp/primitive_kind.hpp"
#include "models/protocol/packet.hpp"

namespace pp5 {

class SetupMemo {
 public:
  // What set-up depends on besides the scene.
  struct Key {
    GeometryParams params;
    std::vector<ExpressionSet> expressions;  // per primitive kind, its procedure's
    std::vector<std::uint64_t> words;        // per primitive kind, its packet's ring words
  };
  // A packet and the regions it was binned to: regions[first, first + count).
  struct Placed {
    std::shared_ptr<const Packet> packet;
    std::uint32_t first = 0;
    std::uint32_t count = 0;
  };
  // One primitive: its kind, its tally, what its transform and set-ups counted, and its packets
  // placed[first, first + count).
  struct Record {
    bool filled = false;
    int kind = 0;  // its primitive kind: index in primitive_kinds()
    PrimitiveTally tally;
    std::uint32_t first = 0;
    std::uint32_t count = 0;
    // Its set-up counts, counts(record): most primitives count nothing, and keep no copy.
    std::uint32_t counted = kNothingCounted;
  };
  static constexpr std::uint32_t kNothingCounted = 0xffffffffu;

  explicit SetupMemo(const Scene& scene) : scene_(&scene) {}
  // Its summary points into its records: not copied.
  SetupMemo(const SetupMemo&) = delete;
  SetupMemo& operator=(const SetupMemo&) = delete;

  const Scene& scene() const { return *scene_; }
  // Keeps the records if `key` is the memo's, else empties it for a display list of
  // `primitives`. Returns whether the records were kept.
  bool bind(const Key& key, std::size_t primitives);

  const Record& record(int primitive) const {
    return records_[static_cast<std::size_t>(primitive)];
  }
  const Placed& placed(std::uint32_t k) const { return placed_[k]; }
  // What a record's transform and set-ups counted.
  const SetupCounts& counts(const Record& r) const {
    static const SetupCounts nothing{};
    return r.counted == kNothingCounted ? nothing : counted_[r.counted];
  }
  int region(std::uint32_t k) const { return regions_[k]; }

  // Filling primitive `primitive`'s record: begin, then place each packet, then end.
  void begin(int primitive);
  void place(std::shared_ptr<const Packet> packet, const std::vector<int>& regions);
  void end(int primitive, int kind, const PrimitiveTally& tally, const SetupCounts& counts);

  // Whether every primitive's record is filled, or none is.
  bool complete() const { return filled_ == records_.size(); }
  bool empty() const { return filled_ == 0; }
  const Key& key() const { return key_; }

  // Takes over the records of primitives [first, last) from `part`, a memo of the same
  // scene and key that holds those and no others, as if this memo had filled them itself;
  // this memo must hold none at or after `first`, and the parts come in display-list order
  // (fill_setup_memo, models/gp/graphics_processor.hpp, fills parts on several threads).
  void absorb(SetupMemo&& part, int first, int last);

  // The records by what the GPs' costs and the Renderers' cycles depend on. A GP's share of
  // the display list is a contiguous block, so each sum over a block comes from a few
  // counts, not from one step per primitive.
  struct Summary {
    // The distinct (kind, tally) pairs met, each with the primitives of it: a GP's i860
    // operations depend on nothing else (PrimitiveKind::operations).
    struct TallyClass {
      int kind = 0;
      PrimitiveTally tally;
    };
    std::vector<TallyClass> classes;
    std::vector<std::uint32_t> class_of;  // per primitive
    // Per class, the primitives of it before primitive kCheckpoint * j:
    // checkpoints[j * classes.size() + c]. Only for up to kMaxCheckpointed classes (a few
    // usually: their size grows with the classes); beyond, a block is counted primitive by
    // primitive.
    static constexpr int kCheckpoint = 64;
    static constexpr std::size_t kMaxCheckpointed = 256;
    std::vector<std::uint32_t> checkpoints;
    // The primitives whose set-up counted something (most count nothing), in order.
    std::vector<std::pair<int, SetupCounts>> counted;
    // Per region, its packets in display-list order: packet k of region r is
    // region_packets[region_first[r] + k], from primitive region_primitive[...].
    std::vector<std::uint32_t> region_first;  // regions + 1
    std::vector<int> region_primitive;
    std::vector<const std::shared_ptr<const Packet>*> region_packets;
    std::vector<std::uint32_t> region_words;  // each packet's ring words (Packet::words)
    // Every packet's words, when all have the same (one primitive kind), else 0.
    std::uint64_t uniform_words = 0;
    // Per region, its packets by what a Renderer's cycles for one depend on (procedure,
    // solid, facing): signature_first[r] .. signature_first[r + 1] into `signatures`.
    struct Signature {
      const Packet* example = nullptr;  // one packet of the signature
      std::uint32_t count = 0;
    };
    std::vector<std::uint32_t> signature_first;  // regions + 1
    std::vector<Signature> signatures;

    // Per class, the primitives of it in [first, last), into `out` (classes.size()).
    void count_classes(int first, int last, std::vector<std::uint32_t>& out) const;
  };
  // Built on first use after the memo is complete; `regions` is the frame's region count.
  const Summary& summary(int regions);

  // Frames bound with a matching key (bind returned true), for tests and reports.
  std::uint64_t reuses() const { return reuses_; }

 private:
  const Scene* scene_;
  bool bound_ = false;
  Key key_;
  std::vector<Record> records_;
  std::vector<Placed> placed_;
  std::vector<int> regions_;
  std::vector<SetupCounts> counted_;  // the records' counts that are not all 0
  std::size_t filled_ = 0;
  std::unique_ptr<Summary> summary_;
  std::uint64_t reuses_ = 0;
};

}  // namespace pp5
