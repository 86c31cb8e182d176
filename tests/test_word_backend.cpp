// The word backend against the bit backend: (a) whole frames, every shipped program with
// every built-in scene, the whole pixel memory of every region compared after the region;
// (b) a scoreboard running random instruction streams on both backends in lockstep and
// comparing all memory, E and the stack after every instruction. Seeded, so every run tests
// the same streams.
#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <deque>
#include <filesystem>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "firmware/isa/isa.hpp"
#include "models/pixel_array/backends.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/scene/scene.hpp"
#include "sim/simulation.hpp"
#include "support.hpp"

namespace fs = std::filesystem;
using namespace pp5;

namespace {

std::vector<std::string> shipped_programs() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(fs::path(PP5_SOURCE_DIR) / "firmware" / "programs")) {
    if (e.path().extension() == ".pp5") names.push_back(e.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// Every region's whole pixel memory (the snapshot layout), E and stack depth after the region,
// keyed by region.
struct RegionMemory {
  std::vector<std::uint64_t> planes;
  int enabled = 0;
  int depth = 0;
};

class Keeper final : public BoardObserver {
 public:
  explicit Keeper(std::map<int, RegionMemory>& out) : out_(out) {}
  void begin_packet(const PacketContext&, const ProcedureCode&, const RendererBoard&) override {}
  void after_instruction(int, const Instruction&, ArrayCycles, const RendererBoard&) override {}
  void end_region(int region, const RendererBoard& board) override {
    RegionMemory& m = out_[region];
    board.array().read_memory_planes(m.planes);
    m.enabled = board.array().count_enabled();
    m.depth = board.array().enable_depth();
  }

 private:
  std::map<int, RegionMemory>& out_;
};

// Runs the frame at `level` with a keeper on every board; each Renderer owns its regions, so
// the maps of the boards never share a key.
std::map<int, RegionMemory> frame_memory(MachineConfig config, const char* level,
                                         const Scene& scene, const Program& program,
                                         RgbImage& image) {
  config.set(std::string("fidelity.pixels=") + level);
  std::vector<std::map<int, RegionMemory>> per_board(
      static_cast<std::size_t>(config.renderer.count));
  std::vector<std::unique_ptr<Keeper>> keepers;
  for (auto& m : per_board) keepers.push_back(std::make_unique<Keeper>(m));
  FrameResult r = simulate_frame(config, scene, program, 2,
                                 [&](int k) -> BoardObserver* { return keepers[k].get(); });
  image = r.image.flat();
  std::map<int, RegionMemory> all;
  for (auto& m : per_board) all.insert(m.begin(), m.end());
  return all;
}

}  // namespace

TEST_CASE("word leaves every region's whole pixel memory as bit does: every program x scene",
          "[word][backend]") {
  MachineConfig config = MachineConfig::defaults();
  // Four regions of 64 x 64, two Renderers, so that a board runs regions one after another
  // on the memory the previous one left; small, so that 2 x 78 frames take seconds.
  config.set({"screen.width=128", "screen.height=128", "renderer.region_width=64",
              "renderer.region_height=64", "gp.count=2", "renderer.count=2"});
  for (const std::string& scene_name : builtin_scene_names()) {
    // Tessellated scenes coarser than their defaults (thousands of triangles in four small
    // regions would take minutes); the fixed ones as they are.
    Scene scene;
    try {
      scene = make_builtin_scene(scene_name, SceneOptions{24, 12});
    } catch (const std::invalid_argument&) {
      scene = make_builtin_scene(scene_name);
    }
    for (const std::string& name : shipped_programs()) {
      INFO("scene " << scene_name << ", program " << name);
      const Program program = test::load_program(name, config);
      // Scenes of spheres only with the programs that draw them (the others refuse them).
      if (!scene.spheres.empty() && !program.procedure(Procedure::sphere).defined) continue;
      RgbImage bit_image, word_image;
      const auto bit = frame_memory(config, "bit", scene, program, bit_image);
      const auto word = frame_memory(config, "word", scene, program, word_image);
      REQUIRE(bit.size() == static_cast<std::size_t>(config.regions()));
      REQUIRE(word.size() == bit.size());
      for (const auto& [region, want] : bit) {
        INFO("region " << region);
        const RegionMemory& got = word.at(region);
        REQUIRE(got.planes.size() == want.planes.size());
        CHECK(got.planes == want.planes);
        CHECK(got.enabled == want.enabled);
        CHECK(got.depth == want.depth);
      }
      CHECK(word_image.rgb == bit_image.rgb);
    }
  }
}

namespace {

// Random instruction streams that stress what a whole-field backend could get wrong: fields
// of every width up to 64 at every alignment (straddling 64-bit lanes), signed and unsigned,
// sources overlapping their destination from above and below, 64-bit unsigned compares,
// constants of every size, quadratic expressions with cross terms, the backing store and
// the Enable stack at its limits.
class Scoreboard {
 public:
  Scoreboard(const PixelBackendParams& p, unsigned seed)
      : p_(p),
        rng_(seed),
        bit_(make_pixel_backend("bit", p)),
        word_(make_pixel_backend("word", p)) {}

  // Compared after every instruction, or (each = false) only after each packet: reading a
  // backend's state applies what it defers (a run of linear tests), so only the second lets
  // deferred work meet the instructions after it.
  void run(int packets, int per_packet, bool each = true) {
    x0_ = static_cast<int>(pick(-300, 3000));
    y0_ = static_cast<int>(pick(-300, 3000));
    bit_->set_origin(x0_, y0_);
    word_->set_origin(x0_, y0_);
    std::mt19937_64 fill(rng_());
    for (int px = 0; px < bit_->pixels(); ++px) {
      for (int lo = 0; lo < p_.array.memory_bits; lo += 64) {
        const Field f{lo, std::min(64, p_.array.memory_bits - lo), false};
        const std::uint64_t v = fill();
        bit_->write(px, f, v);
        word_->write(px, f, v);
      }
    }
    same("initial memory");
    for (int k = 0; k < packets; ++k) {
      const OwnedValues values = make_values();
      for (int n = 0; n < per_packet; ++n) {
        const Instruction ins = next();
        const std::string what =
            fmt::format("packet {} instruction {}: {}", k, n, disassemble(ins));
        // Odd packets run mul's windowed microcode on both backends.
        ExecutionContext cb{*bit_, values, p_.fraction_bits, k % 2 == 1};
        ExecutionContext cw{*word_, values, p_.fraction_bits, k % 2 == 1};
        instruction_info(ins.op).execute(ins, cb);
        instruction_info(ins.op).execute(ins, cw);
        ++executed_[static_cast<std::size_t>(ins.op)];
        if (each) same(what);
      }
      if (!each) same(fmt::format("the end of packet {}", k));
    }
  }
  const std::vector<int>& executed() const { return executed_; }
  // The shares of instructions (percent) drawn as qload, as qtest, as a mov of a constant
  // and as a clamp (epush, cmp of a field with a constant, mov of a constant into it, epop;
  // now and then more writes before the epop, or none) before any other draw: runs of writes that
  // read no pixel memory, as a triangle's attributes are, with fields overlapping and across lanes,
  // tests between them, and the Enable stack around a compare, as the lighting's and a sphere's
  // clamps use it.
  void favour(int qload_percent, int qtest_percent, int mov_constant_percent,
              int clamp_percent = 0) {
    qload_percent_ = qload_percent;
    qtest_percent_ = qtest_percent;
    mov_constant_percent_ = mov_constant_percent;
    clamp_percent_ = clamp_percent;
  }

 private:
  void same(const std::string& what) {
    INFO(what);
    REQUIRE(word_->enable_depth() == bit_->enable_depth());
    bit_->read_memory_planes(bit_planes_);
    word_->read_memory_planes(word_planes_);
    REQUIRE(word_planes_.size() == bit_planes_.size());
    if (word_planes_ != bit_planes_) {
      const int words = bit_->pixels() / 64;
      for (std::size_t i = 0; i < bit_planes_.size(); ++i) {
        INFO("bit " << i / words << ", pixels from " << (i % words) * 64);
        REQUIRE(word_planes_[i] == bit_planes_[i]);
      }
    }
    for (int px = 0; px < bit_->pixels(); ++px) {
      if (word_->enabled(px) != bit_->enabled(px)) {
        INFO("E of pixel " << px);
        REQUIRE(word_->enabled(px) == bit_->enabled(px));
      }
    }
    REQUIRE(word_->count_enabled() == bit_->count_enabled());
    // The colour read-out: three whole bytes of one lane (word's one-pass shuffle), the same
    // in the lane above, and three fields of any width and place (its generic reads).
    const int top = (p_.array.memory_bits - 24) / 8 * 8;
    const int lane_top = std::min(top, 40);
    const Field bytes[3] = {
        {lane_top, 8, false}, {lane_top - 16, 12, true}, {lane_top + 8, 8, false}};
    const Field above[3] = {{top, 8, false}, {top + 8, 8, false}, {top + 16, 8, false}};
    const Field any[3] = {any_field().field, any_field().field, any_field().field};
    for (const Field* f : {bytes, above, any}) {
      bit_->read_bytes(f, 3, bit_bytes_.data());
      word_->read_bytes(f, 3, word_bytes_.data());
      REQUIRE(word_bytes_ == bit_bytes_);
    }
  }

  std::int64_t pick(std::int64_t lo, std::int64_t hi) {
    return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng_);
  }
  std::int64_t any_bits(int bits) {
    if (bits >= 64) return static_cast<std::int64_t>(rng_());
    return pick(-(std::int64_t{1} << (bits - 1)), (std::int64_t{1} << (bits - 1)) - 1);
  }

  OwnedValues make_values() {
    OwnedValues v;
    const int c = p_.evaluator.coefficient_bits;
    for (auto& e : v.expressions) {
      switch (pick(0, 4)) {
        case 4: {  // a plane whose zero crosses the region (a triangle's edge)
          e.D = pick(-(1 << 12), 1 << 12);
          e.E = pick(-(1 << 12), 1 << 12);
          const std::int64_t x = x0_ + pick(0, p_.array.width - 1);
          const std::int64_t y = y0_ + pick(0, p_.array.height - 1);
          e.F = -(e.D * x + e.E * y) + pick(-(1 << 12), 1 << 12);
          break;
        }
        case 0:  // a constant
          e.F = any_bits(c);
          break;
        case 1:  // a plane of ordinary slope
          e.D = pick(-(1 << 16), 1 << 16);
          e.E = pick(-(1 << 16), 1 << 16);
          e.F = any_bits(std::min(c, 36));
          break;
        case 2:  // coefficients of any size: the value wraps
          e.D = any_bits(c);
          e.E = any_bits(c);
          e.F = any_bits(c);
          break;
        default:  // quadratic, with a cross term
          e.A = pick(-5000, 5000);
          e.B = pick(-5000, 5000);
          e.C = pick(-5000, 5000);
          e.D = pick(-(1 << 20), 1 << 20);
          e.E = pick(-(1 << 20), 1 << 20);
          e.F = any_bits(std::min(c, 40));
          break;
      }
    }
    for (auto& k : v.parameters)
      k = pick(0, 1) ? pick(-1000, 1000) : any_bits(static_cast<int>(pick(1, 64)));
    return v;
  }

  Operand field(int lo_min, int lo_max_end, int max_width = 64) {
    Operand o;
    o.kind = Operand::Kind::field;
    const int room = lo_max_end - lo_min;
    o.field.width = static_cast<int>(pick(1, std::min(max_width, room)));
    // Widths 1 and 64 and lane boundaries are where a shift or a mask goes wrong.
    if (pick(0, 4) == 0) o.field.width = std::min(room, pick(0, 1) ? 64 : 1);
    o.field.lo = static_cast<int>(pick(lo_min, lo_max_end - o.field.width));
    o.field.is_signed = pick(0, 1) == 1;
    o.text = fmt::format("[{}+{}{}]", o.field.lo, o.field.width, o.field.is_signed ? "s" : "");
    return o;
  }
  Operand any_field() { return field(0, p_.array.memory_bits); }
  // A field overlapping `d`, starting below it, at it or above it.
  Operand overlapping(const Field& d) {
    Operand o = any_field();
    const int lo = static_cast<int>(pick(std::max(0, d.lo - 20), d.lo + d.width - 1));
    const int width =
        static_cast<int>(pick(std::max(1, d.lo - lo + 1), std::min(64, p_.array.memory_bits - lo)));
    o.field.lo = lo;
    o.field.width = width;
    o.text = fmt::format("[{}+{}{}]", lo, width, o.field.is_signed ? "s" : "");
    return o;
  }
  Operand constant() {
    Operand o;
    if (pick(0, 1) == 0) {
      o.kind = Operand::Kind::parameter;
      o.index = static_cast<int>(pick(0, static_cast<int>(Parameter::count) - 1));
      o.text = parameter_name(static_cast<Parameter>(o.index));
    } else {
      o.kind = Operand::Kind::literal;
      o.literal = any_bits(static_cast<int>(pick(1, 64)));
    }
    return o;
  }
  Operand expression() {
    Operand o;
    o.kind = Operand::Kind::expression;
    o.index = static_cast<int>(pick(0, static_cast<int>(Expression::count) - 1));
    o.text = kExpressions[o.index].name;
    return o;
  }

  Instruction next() {
    if (!queued_.empty()) {
      const Instruction q = queued_.front();
      queued_.pop_front();
      return q;
    }
    Instruction i;
    i.condition = static_cast<Compare>(pick(0, 5));
    const int depth = bit_->enable_depth();
    for (;;) {
      i.op = static_cast<Opcode>(pick(0, static_cast<int>(Opcode::count) - 1));
      const auto share = pick(0, 99);
      if (share < qload_percent_) {
        i.op = Opcode::qload;
      } else if (share < qload_percent_ + qtest_percent_) {
        i.op = Opcode::qtest;
      } else if (share < qload_percent_ + qtest_percent_ + mov_constant_percent_) {
        i.op = Opcode::mov;
        i.operands[0] = any_field();
        i.operands[1] = constant();
        return i;
      } else if (share < qload_percent_ + qtest_percent_ + mov_constant_percent_ + clamp_percent_ &&
                 depth < p_.array.enable_stack_depth) {
        Instruction cmp = i, mov, pop;
        cmp.op = Opcode::cmp;
        cmp.operands[0] = any_field();
        // A constant within the field's range, so that the compare leaves some pixels of a
        // row and clears others.
        const Field& f = cmp.operands[0].field;
        const int bits = std::min(f.width, 62);
        cmp.operands[1].kind = Operand::Kind::literal;
        cmp.operands[1].literal = f.is_signed ? pick(-(std::int64_t{1} << (bits - 1)),
                                                     (std::int64_t{1} << (bits - 1)) - 1)
                                              : pick(0, (std::int64_t{1} << bits) - 1);
        mov.op = Opcode::mov;
        mov.operands[0] = cmp.operands[0];
        mov.operands[1] = constant();
        pop.op = Opcode::epop;
        queued_ = {cmp};
        // Before and after the clamp's own mov, now and then other writes under the
        // compare's E: constants into any field (the clamp's own among them), a qload, or
        // none at all (a compare whose E nothing uses before the epop).
        const int extras = static_cast<int>(pick(0, 3));
        const int own = static_cast<int>(pick(0, extras));
        for (int x = 0; x <= extras; ++x) {
          if (x == own) {
            if (pick(0, 5) != 0) queued_.push_back(mov);
            continue;
          }
          Instruction w;
          w.op = pick(0, 3) == 0 ? Opcode::qload : Opcode::mov;
          w.operands[0] = pick(0, 2) == 0 ? cmp.operands[0] : any_field();
          w.operands[1] = w.op == Opcode::qload ? expression() : constant();
          queued_.push_back(w);
        }
        queued_.push_back(pop);
        i.op = Opcode::epush;
        return i;
      }
      if (i.op == Opcode::epush && depth >= p_.array.enable_stack_depth) continue;
      if ((i.op == Opcode::epop || i.op == Opcode::eelse) && depth == 0) continue;
      // Keep some pixels enabled most of the time, as firmware does.
      if (i.op == Opcode::eall && pick(0, 2) != 0) continue;
      break;
    }
    auto& o = i.operands;
    const int half = p_.array.memory_bits / 2;
    switch (i.op) {
      case Opcode::qtest:
        o[0] = expression();
        break;
      case Opcode::qload:
      case Opcode::qcmp:
        o[0] = any_field();
        o[1] = expression();
        break;
      case Opcode::mov:
      case Opcode::add:
      case Opcode::sub:
      case Opcode::cmp:
      case Opcode::and_:
      case Opcode::or_:
      case Opcode::xor_: {
        o[0] = any_field();
        const auto kind = pick(0, 3);
        o[1] = kind == 0 ? constant() : kind == 1 ? overlapping(o[0].field) : any_field();
        break;
      }
      case Opcode::not_:
        o[0] = any_field();
        break;
      case Opcode::mul:
        o[0] = field(half, p_.array.memory_bits);
        o[1] = field(0, half);
        o[2] = field(0, half);
        break;
      case Opcode::mac:
        o[0] = field(half, p_.array.memory_bits);
        o[1] = field(0, half);
        o[2] = constant();
        break;
      case Opcode::bsld:
      case Opcode::bsst: {
        o[0] = any_field();
        const int blocks = (o[0].field.width + p_.array.block_bits - 1) / p_.array.block_bits;
        o[1].kind = Operand::Kind::literal;
        o[1].literal = pick(0, p_.array.backing_store_bits / p_.array.block_bits - blocks);
        break;
      }
      default:
        break;
    }
    return i;
  }

  PixelBackendParams p_;
  std::mt19937_64 rng_;
  std::unique_ptr<PixelBackend> bit_;
  std::unique_ptr<PixelBackend> word_;
  std::vector<std::uint64_t> bit_planes_, word_planes_;
  std::vector<std::uint8_t> bit_bytes_ = std::vector<std::uint8_t>(
                                static_cast<std::size_t>(p_.array.width * p_.array.height * 3)),
                            word_bytes_ = bit_bytes_;
  std::vector<int> executed_ = std::vector<int>(static_cast<std::size_t>(Opcode::count), 0);
  int qload_percent_ = 0, qtest_percent_ = 0, mov_constant_percent_ = 0, clamp_percent_ = 0;
  std::deque<Instruction> queued_;  // the rest of a clamp
  int x0_ = 0, y0_ = 0;             // the region's origin (run)
};

}  // namespace

namespace {

// A scoreboard's board: its array and evaluator, the Enable stack and backing store fixed.
struct ScoreShape {
  int width, height, memory_bits, result_bits, coefficient_bits, fraction_bits;
};

PixelBackendParams score_params(const ScoreShape& s) {
  PixelBackendParams p;
  p.array.width = s.width;
  p.array.height = s.height;
  p.array.memory_bits = s.memory_bits;
  p.array.enable_stack_depth = 4;
  p.array.backing_store_bits = 512;
  p.array.block_bits = 32;
  p.evaluator.coefficient_bits = s.coefficient_bits;
  p.evaluator.result_bits = s.result_bits;
  p.fraction_bits = s.fraction_bits;
  return p;
}

}  // namespace

TEST_CASE("word and bit run random instruction streams in lockstep (scoreboard)",
          "[word][backend]") {
  using Shape = ScoreShape;
  // The real board's memory (208 bits: four 64-bit lanes, the last partial), a narrow one,
  // a 64-bit evaluator result, no fraction bits and many.
  const Shape shapes[] = {{128, 8, 208, 40, 40, 12},
                          {64, 3, 70, 64, 62, 0},
                          {192, 2, 130, 48, 30, 20},
                          {128, 4, 256, 64, 40, 63}};
  std::vector<int> executed(static_cast<std::size_t>(Opcode::count), 0);
  unsigned seed = 1;
  for (const Shape& s : shapes) {
    for (int k = 0; k < 4; ++k, ++seed) {
      INFO("shape " << s.width << "x" << s.height << ", " << s.memory_bits << " bits, seed "
                    << seed);
      const PixelBackendParams p = score_params(s);
      Scoreboard board(p, seed);
      board.run(6, 80);
      for (std::size_t op = 0; op < executed.size(); ++op) executed[op] += board.executed()[op];
      Scoreboard packets(p, seed + 1000);
      packets.run(12, 40, false);
    }
  }
  for (std::size_t op = 0; op < executed.size(); ++op) {
    INFO("opcode " << instruction_info(static_cast<Opcode>(op)).mnemonic);
    CHECK(executed[op] > 10);
  }
}

TEST_CASE("word and bit agree on runs of qloads and constant movs (word writes a run in one walk)",
          "[word][backend]") {
  // Mostly qloads and movs of constants, compared only after each packet: runs longer than
  // the word backend keeps waiting, to fields that overlap (the later write wins) and lie in
  // different lanes, with linear and quadratic expressions, broken by tests and the other
  // instructions that must write them first (and compared after every instruction in a
  // second run, where each read does).
  const PixelBackendParams p = score_params({128, 6, 208, 40, 40, 12});
  for (unsigned seed = 1; seed <= 6; ++seed) {
    INFO("seed " << seed);
    Scoreboard runs(p, seed);
    runs.favour(seed % 2 == 0 ? 60 : 40, 15, 10, 10);
    runs.run(10, 40, false);
    CHECK(runs.executed()[static_cast<std::size_t>(Opcode::qload)] > 100);
    CHECK(runs.executed()[static_cast<std::size_t>(Opcode::epush)] > 12);
    Scoreboard each(p, seed + 100);
    each.favour(40, 15, 10, 10);
    each.run(2, 40);
  }
}

TEST_CASE("the word backend's state: empty-region reuse and a bad geometry", "[word][backend]") {
  PixelBackendParams p;
  p.array.width = 64;
  p.array.height = 2;
  p.array.memory_bits = 100;
  auto a = make_pixel_backend("word", p);
  auto b = make_pixel_backend("word", p);
  // A backing store that was never allocated is the same state as one that holds zeros.
  b->store_to_backing(Field{0, 8, false}, 0);
  CHECK(a->same_state(*b));
  a->write(3, Field{60, 10, false}, 0x3ff);  // across the first lane boundary
  CHECK(a->read(3, Field{60, 10, false}) == 0x3ff);
  CHECK(a->read(3, Field{59, 12, false}) == 0x7fe);
  CHECK_FALSE(a->same_state(*b));
  b->copy_state_from(*a);
  CHECK(a->same_state(*b));
  // After eall, E's bytes are filled only when something reads E; a state taken from another
  // in the meantime is that state's E, not all 1.
  for (int px = 0; px < 128; ++px) b->write(px, Field{90, 1, false}, px % 2);
  b->enable_all();
  b->compare(Field{90, 1, false}, Source::of(1), Compare::eq);  // the odd pixels
  CHECK(b->count_enabled() == 64);
  a->enable_all();
  a->copy_state_from(*b);
  CHECK(a->count_enabled() == 64);
  CHECK(a->same_state(*b));
  // Not the state of a bit backend, even an equal one.
  auto bit = make_pixel_backend("bit", p);
  CHECK_FALSE(a->same_state(*bit));
  CHECK_THROWS_AS(a->copy_state_from(*bit), std::invalid_argument);
  p.array.width = 100;
  CHECK_THROWS_AS(make_pixel_backend("word", p), std::invalid_argument);
}

TEST_CASE("word and bit agree on runs of linear tests (both backends apply them together)",
          "[word][backend]") {
  // Runs of one to five half-plane tests after eall, as a triangle's edges (both backends
  // defer up to four and test only the rows of their band, models/evaluator/linear_band.hpp),
  // with every condition, edges of every slope (D or E zero too), regions anywhere on the
  // screen; then a test they cannot defer (eq), a save, another run and a restore. E must be
  // the same pixel for pixel, and the same as a bit backend's that applies each test on its
  // own (`each`: reading E after every test makes it apply what it holds back), so that a
  // fault in the band, which both deferring backends share, cannot hide.
  PixelBackendParams p;
  p.array.width = 128;
  p.array.height = 128;
  p.array.memory_bits = 64;
  p.array.enable_stack_depth = 2;
  p.evaluator.coefficient_bits = 40;
  p.evaluator.result_bits = 40;
  p.fraction_bits = 8;
  auto word = make_pixel_backend("word", p);
  auto bit = make_pixel_backend("bit", p);
  auto each = make_pixel_backend("bit", p);
  std::mt19937_64 rng(20261125);
  auto uniform = [&](std::int64_t lo, std::int64_t hi) {
    return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng);
  };
  const Compare one_interval[] = {Compare::lt, Compare::le, Compare::gt, Compare::ge};
  int x0 = 0, y0 = 0;
  auto edge = [&] {
    QuadraticCoefficients c;
    const int kind = static_cast<int>(uniform(0, 9));
    c.D = kind == 0 ? 0 : uniform(-4096, 4096);
    c.E = kind == 1 ? 0 : uniform(-4096, 4096);
    // Through a point near the region (the value is D (x0 + x) + E (y0 + y) + F), so that
    // the edge usually crosses it.
    const std::int64_t px = x0 + uniform(-32, 160), py = y0 + uniform(-32, 160);
    c.F = -(c.D * px + c.E * py) + uniform(-2048, 2048);
    return c;
  };
  auto same_enable = [&](const char* when) {
    INFO(when);
    int differing = 0;
    int differing_each = 0;
    for (int px = 0; px < 128 * 128; ++px) {
      differing += word->enabled(px) != bit->enabled(px);
      differing_each += bit->enabled(px) != each->enabled(px);
    }
    REQUIRE(differing == 0);
    REQUIRE(differing_each == 0);
    REQUIRE(word->count_enabled() == bit->count_enabled());
  };
  int narrowed = 0;
  for (int trial = 0; trial < 400; ++trial) {
    INFO("trial " << trial);
    x0 = static_cast<int>(uniform(-2, 30)) * 128;
    y0 = static_cast<int>(uniform(-2, 30)) * 128;
    for (auto* b : {word.get(), bit.get(), each.get()}) b->set_origin(x0, y0);
    for (auto* b : {word.get(), bit.get(), each.get()}) b->enable_all();
    const int run = static_cast<int>(uniform(1, 5));
    for (int k = 0; k < run; ++k) {
      const QuadraticCoefficients c = edge();
      const Compare cond = one_interval[uniform(0, 3)];
      word->qtest(c, cond);
      bit->qtest(c, cond);
      each->qtest(c, cond);
      (void)each->count_enabled();  // applies the test now
    }
    same_enable("after the run");
    const int left = word->count_enabled();
    narrowed += left > 0 && left < 128 * 128;
    const QuadraticCoefficients eq = edge();
    for (auto* b : {word.get(), bit.get(), each.get()}) b->push_enable();
    for (auto* b : {word.get(), bit.get(), each.get()}) b->qtest(eq, Compare::ne);
    for (int k = 0; k < 3; ++k) {
      const QuadraticCoefficients c = edge();
      word->qtest(c, Compare::ge);
      bit->qtest(c, Compare::ge);
      each->qtest(c, Compare::ge);
      (void)each->count_enabled();
    }
    same_enable("after a save and another run");
    for (auto* b : {word.get(), bit.get(), each.get()}) b->pop_enable();
    same_enable("after the restore");
  }
  CHECK(narrowed > 100);
}

TEST_CASE("word and bit agree on quadratic tests (word finds each row's interval exactly)",
          "[word][backend]") {
  // The word backend's qtest of a quadratic expression (lt, le, gt, ge) finds on each row of
  // its spans the interval where the condition holds, or its complement, by binary search
  // on exact values, and runs the per-pixel evaluation instead when the value could wrap on
  // some row. Random discs and ellipses (convex and concave, with a cross term), rows linear
  // in x (A = 0, B != 0) or constant (A = B = 0, C != 0), of every size from one pixel to
  // more than the region, every condition; before the test E narrowed by edges (spans that
  // start inside a row) and by a cmp on random memory (holes inside the spans); values
  // shifted so that their extreme lies a few units either side of the wrap limit, so that
  // both paths run; coefficients sent modulo 2^result_bits as a sphere's are. E and memory compared
  // with bit after the test and after a write under E.
  PixelBackendParams p;
  p.array.width = 128;
  p.array.height = 48;
  p.array.memory_bits = 64;
  p.array.enable_stack_depth = 2;
  // 40 result bits: word's search in 64-bit integers; 56: in 128-bit ones.
  const int result_bits = GENERATE(40, 56);
  INFO("result_bits " << result_bits);
  p.evaluator.coefficient_bits = 40;
  p.evaluator.result_bits = result_bits;
  p.fraction_bits = 8;
  const int width = p.array.width, height = p.array.height;
  auto word = make_pixel_backend("word", p);
  auto bit = make_pixel_backend("bit", p);
  std::mt19937_64 rng(20261127);
  auto uniform = [&](std::int64_t lo, std::int64_t hi) {
    return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng);
  };
  for (int px = 0; px < width * height; ++px) {
    const std::uint64_t v = rng();
    word->write(px, Field{0, 64, false}, v);
    bit->write(px, Field{0, 64, false}, v);
  }
  using i128 = __int128;
  const i128 limit = i128(1) << (p.evaluator.result_bits - 1);
  std::vector<std::uint64_t> bit_planes, word_planes;
  auto same = [&](const char* when) {
    INFO(when);
    int differing = 0;
    for (int px = 0; px < width * height; ++px) differing += word->enabled(px) != bit->enabled(px);
    REQUIRE(differing == 0);
    REQUIRE(word->count_enabled() == bit->count_enabled());
    bit->read_memory_planes(bit_planes);
    word->read_memory_planes(word_planes);
    REQUIRE(word_planes == bit_planes);
  };
  int partial = 0, wrapped = 0, near = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    INFO("trial " << trial);
    // Sometimes far from the screen's origin: coefficients beyond result_bits (below).
    const int far = uniform(0, 3) == 0 ? 4096 : 20;
    const int x0 = static_cast<int>(uniform(-3, far)) * width;
    const int y0 = static_cast<int>(uniform(-3, far)) * height;
    for (auto* b : {word.get(), bit.get()}) b->set_origin(x0, y0);
    for (auto* b : {word.get(), bit.get()}) b->enable_all();
    const int before = static_cast<int>(uniform(0, 3));
    if (before & 1) {  // an edge: spans that start inside rows
      const std::int64_t d = uniform(-300, 300), e = uniform(-300, 300);
      const QuadraticCoefficients edge = QuadraticCoefficients::linear(
          d, e, -(d * (x0 + uniform(0, width)) + e * (y0 + uniform(0, height))));
      const Compare side = uniform(0, 1) ? Compare::ge : Compare::lt;
      for (auto* b : {word.get(), bit.get()}) b->qtest(edge, side);
    }
    if (before & 2) {  // E = 0 at random pixels inside the spans
      const Field f{static_cast<int>(uniform(0, 56)), 3, false};
      for (auto* b : {word.get(), bit.get()})
        b->compare(f, Source::of(std::int64_t{1}), Compare::ne);
    }
    // g = A (X - cx)^2 + B (X - cx)(Y - cy) + C (Y - cy)^2 + G, expanded.
    const std::int64_t cx = x0 + uniform(-40, width + 40), cy = y0 + uniform(-40, height + 40);
    std::int64_t A = 0, B = 0, C = 0, G = 0;
    const int kind = static_cast<int>(uniform(0, 5));
    const std::int64_t sign = uniform(0, 1) ? 1 : -1;
    if (kind <= 2) {  // an ellipse: convex (sign 1) or concave (-1), radius 0 to beyond the region
      A = sign * uniform(1, 9);
      C = sign * uniform(1, 9);
      B = kind == 0 ? 0 : uniform(-1, 1) * std::min(std::abs(A), std::abs(C));
      const std::int64_t r = uniform(0, 3) == 0 ? uniform(0, 2) : uniform(0, 160);
      G = -sign * 4 * r * r + uniform(-3, 3);
    } else if (kind == 3) {  // linear in x on each row
      B = uniform(1, 50) * (uniform(0, 1) ? 1 : -1);
      C = uniform(-3, 3);
      G = uniform(-100000, 100000);
    } else if (kind == 4) {  // constant on each row
      C = uniform(1, 40) * sign;
      G = uniform(-40000, 40000);
    } else {  // a parabola in x: one to a few pixels where it changes sign
      A = sign * uniform(1, 3000);
      G = -sign * uniform(0, 20);
    }
    QuadraticCoefficients c;
    c.A = A;
    c.B = B;
    c.C = C;
    c.D = -2 * A * cx - B * cy;
    c.E = -2 * C * cy - B * cx;
    c.F = A * cx * cx + B * cx * cy + C * cy * cy + G;
    if (uniform(0, 2) == 0) {
      // The value's largest (or smallest) over the region a few units either side of the
      // wrap limit: on that pixel's row the fast path must give way to the per-pixel one.
      i128 most = std::numeric_limits<std::int64_t>::min(), least = -most;
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          const i128 X = x0 + x, Y = y0 + y;
          const i128 v = i128(c.A) * X * X + i128(c.B) * X * Y + i128(c.C) * Y * Y + i128(c.D) * X +
                         i128(c.E) * Y + c.F;
          most = std::max(most, v);
          least = std::min(least, v);
        }
      }
      const i128 shift =
          uniform(0, 1) ? limit - 1 - most + uniform(-2, 2) : -limit - least + uniform(-2, 2);
      c.F += static_cast<std::int64_t>(shift);
      ++near;
      wrapped += most + shift >= limit || least + shift < -limit;
    }
    if (uniform(0, 2) == 0) {
      // Each coefficient sent modulo 2^result_bits, as the GP sends a sphere's (the value
      // is the same modulo 2^result_bits, but formed from coefficients far from it).
      const int s = 64 - p.evaluator.result_bits;
      for (std::int64_t* v : {&c.A, &c.B, &c.C, &c.D, &c.E, &c.F})
        *v = static_cast<std::int64_t>(static_cast<std::uint64_t>(*v) << s) >> s;
    }
    const Compare cond = static_cast<Compare>(uniform(0, 5));
    INFO("A " << c.A << " B " << c.B << " C " << c.C << " D " << c.D << " E " << c.E << " F " << c.F
              << " cond " << static_cast<int>(cond) << " origin " << x0 << "," << y0);
    for (auto* b : {word.get(), bit.get()}) b->qtest(c, cond);
    same("after the quadratic test");
    const int left = word->count_enabled();
    partial += left > 0 && left < width * height / 2;
    const Field dst{static_cast<int>(uniform(0, 48)), 16, false};
    const std::int64_t k = uniform(0, 65535);
    for (auto* b : {word.get(), bit.get()}) b->mov(dst, Source::of(k));
    same("after a write under E");
  }
  CHECK(partial > 300);
  CHECK(wrapped > 50);
  CHECK(near - wrapped > 50);
}

TEST_CASE("word and bit agree on a clamp over rows that start off a multiple of eight",
          "[word][backend]") {
  // Rows from column 3 (an edge test) to the region's end: a row's last chunk of eight is
  // moved back to end at the row's end and so overlaps the chunk before it. A compare right
  // after epush writes the new E into the saved level's buffer (word), where the lanes the
  // moved chunk does not own must keep the chunk before's new bytes. Memory and E after a
  // clamp (epush, cmp, mov, epop) as bit leaves them, for several thresholds.
  const PixelBackendParams p = score_params({128, 4, 64, 40, 40, 0});
  for (const int start : {1, 3, 5}) {
    for (const std::int64_t threshold : {20, 100, 180}) {
      INFO("rows from column " << start << ", threshold " << threshold);
      auto word = make_pixel_backend("word", p);
      auto bit = make_pixel_backend("bit", p);
      std::mt19937_64 rng(static_cast<unsigned>(start * 1000 + threshold));
      for (int px = 0; px < word->pixels(); ++px) {
        const std::uint64_t v = rng();
        word->write(px, Field{0, 64, false}, v);
        bit->write(px, Field{0, 64, false}, v);
      }
      const Field value{8, 8, false}, out{20, 8, false};
      for (PixelBackend* b : {word.get(), bit.get()}) {
        b->enable_all();
        b->qtest(QuadraticCoefficients::linear(1, 0, -start), Compare::ge);  // x >= start
        b->push_enable();
        b->compare(value, Source::of(threshold), Compare::gt);
        b->mov(out, Source::of(0));
        b->pop_enable();
      }
      int differ = 0;
      for (int px = 0; px < word->pixels(); ++px) {
        differ += word->enabled(px) != bit->enabled(px);
        differ += word->read(px, out) != bit->read(px, out);
      }
      CHECK(differ == 0);
    }
  }
}
