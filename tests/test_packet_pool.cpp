// A GP's packet memory kept across frames (models/gp/packet_pool.hpp): packets from a
// reused arena are the packets new memory would hold, and an arena is reused only once
// every packet it handed out has been dropped.
#include <catch2/catch.hpp>
#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "models/gp/graphics_processor.hpp"
#include "models/gp/machine_plan.hpp"
#include "models/gp/packet_pool.hpp"
#include "models/gp/region_bins.hpp"
#include "models/protocol/packet.hpp"
#include "sim/scene/scene.hpp"
#include "tests/support.hpp"

using namespace pp5;
using namespace pp5::test;

namespace {

// A packet by value: its fields and its carried coefficients.
struct PacketCopy {
  Procedure procedure;
  int kind, primitive, group;
  bool back;
  std::uint64_t words;
  std::uint64_t carried;
  std::vector<std::int64_t> coefficients;
  bool operator==(const PacketCopy& o) const {
    return procedure == o.procedure && kind == o.kind && primitive == o.primitive &&
           group == o.group && back == o.back && words == o.words && carried == o.carried &&
           coefficients == o.coefficients;
  }
};

PacketCopy copy_of(const Packet& p) {
  PacketCopy c{
      p.procedure, p.kind, p.primitive, p.group, p.back, p.words, p.values.expressions.carried(),
      {}};
  const ExpressionView view(p.values.expressions);
  for (const QuadraticCoefficients& q : view)
    c.coefficients.insert(c.coefficients.end(), {q.A, q.B, q.C, q.D, q.E, q.F});
  return c;
}

// Every bin's packets, region by region, by value.
std::vector<std::vector<PacketCopy>> contents(const RegionBins& bins) {
  std::vector<std::vector<PacketCopy>> out;
  for (int r : bins.regions()) {
    out.emplace_back();
    for (const auto& p : bins.bin(r)) out.back().push_back(copy_of(*p));
  }
  return out;
}

}  // namespace

TEST_CASE("packet pool: an arena is reused only after its last packet, and gives default packets",
          "[packet_pool]") {
  PacketPool pool;
  std::shared_ptr<PacketArena> arena = pool.take();
  std::set<const Packet*> made;
  std::shared_ptr<const Packet> held;
  for (int k = 0; k < 300; ++k) {  // more than one block
    std::shared_ptr<Packet> p = arena->make(arena);
    p->primitive = k;
    p->group = 7;
    p->back = true;
    p->words = 99;
    p->values.expressions[2] = QuadraticCoefficients::linear(k, 2, 3);
    made.insert(p.get());
    if (k == 123) held = p;
  }
  CHECK(made.size() == 300);
  CHECK(arena->size() == 300);
  const PacketCopy before = copy_of(*held);
  arena.reset();
  CHECK(pool.idle() == 0);  // `held` keeps its arena out of the pool

  std::shared_ptr<PacketArena> second = pool.take();
  for (int k = 0; k < 300; ++k) {
    std::shared_ptr<Packet> p = second->make(second);
    CHECK(made.count(p.get()) == 0);
    p->primitive = -k;
    p->values.expressions[1] = QuadraticCoefficients::linear(1, 1, 1);
  }
  CHECK(copy_of(*held) == before);
  held.reset();
  CHECK(pool.idle() == 1);
  second.reset();
  CHECK(pool.idle() == 2);
  {
    std::shared_ptr<PacketArena> extra = pool.take();  // a third one made, and freed: two kept
    std::shared_ptr<PacketArena> extra2 = pool.take();
    std::shared_ptr<PacketArena> extra3 = pool.take();
    CHECK(pool.idle() == 0);
  }
  CHECK(pool.idle() == 2);

  // A reused arena: its slots again, each a default packet.
  std::shared_ptr<PacketArena> third = pool.take();
  CHECK(third->size() == 0);
  CHECK(third->capacity() >= 300);
  const PacketCopy fresh = copy_of(Packet{});
  std::set<const Packet*> again;
  for (int k = 0; k < 300; ++k) {
    std::shared_ptr<Packet> p = third->make(third);
    CHECK(copy_of(*p) == fresh);
    CHECK(p->values.expressions.size() == 0);
    again.insert(p.get());
  }
  CHECK(pool.idle() == 1);
  CHECK(again.size() == 300);

  // One left waiting while others are taken and given back is freed: memory follows the
  // arenas needed lately.
  {
    PacketPool lately;
    std::shared_ptr<PacketArena> x = lately.take(), y = lately.take();
    x.reset();
    y.reset();
    CHECK(lately.idle() == 2);
    for (int k = 0; k < 8; ++k) lately.take();  // taken and given back at once
    CHECK(lately.idle() == 2);
    lately.take();
    CHECK(lately.idle() == 1);
  }

  // A packet may outlive its pool and arena.
  std::shared_ptr<const Packet> last;
  {
    PacketPool gone;
    std::shared_ptr<PacketArena> a = gone.take();
    std::shared_ptr<Packet> p = a->make(a);
    p->primitive = 5;
    last = p;
  }
  CHECK(last->primitive == 5);
}

TEST_CASE("packet pool: bins reused frame after frame hold the packets new bins would",
          "[packet_pool]") {
  MachineConfig c = MachineConfig::defaults();
  c.screen.width = 256;
  c.screen.height = 256;
  const Program program = load_program("phong", c);
  const Scene coarse = make_builtin_scene("torus", {24, 12});
  const Scene fine = make_builtin_scene("torus", {32, 16});
  const MachinePlan a(c, coarse, program);
  const MachinePlan b(c, fine, program);
  auto fresh_contents = [](const MachinePlan& plan) {
    RegionBins bins;
    GpStats stats;
    geometry_pass(plan, 0, static_cast<int>(plan.geometry().display_list().size()), stats, &bins);
    return contents(bins);
  };
  const auto expect_a = fresh_contents(a);
  const auto expect_b = fresh_contents(b);
  REQUIRE(!expect_a.empty());
  REQUIRE(expect_a != expect_b);

  // One GP's bins, frame after frame, alternating scenes. Each frame's packets are held (as
  // the ring and the Renderers hold them) while the next frame is set up, then dropped.
  RegionBins bins;
  std::vector<std::shared_ptr<const Packet>> in_flight;
  std::vector<std::vector<PacketCopy>> in_flight_then;
  for (int frame = 0; frame < 6; ++frame) {
    const MachinePlan& plan = frame % 2 == 0 ? a : b;
    GpStats stats;
    geometry_pass(plan, 0, static_cast<int>(plan.geometry().display_list().size()), stats, &bins);
    INFO("frame " << frame);
    CHECK(contents(bins) == (frame % 2 == 0 ? expect_a : expect_b));
    // The frame before's packets are as they were when it was set up.
    std::vector<PacketCopy> now;
    for (const auto& p : in_flight) now.push_back(copy_of(*p));
    if (!in_flight_then.empty()) CHECK(now == in_flight_then.back());
    in_flight.clear();
    for (int r : bins.regions())
      in_flight.insert(in_flight.end(), bins.bin(r).begin(), bins.bin(r).end());
    in_flight_then.emplace_back();
    for (const auto& p : in_flight) in_flight_then.back().push_back(copy_of(*p));
  }
}
