#include "sim/trace/recorder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <set>

#include "common/checked_number.hpp"
#include "common/escape.hpp"
#include "sim/trace/trace_file.hpp"

namespace pp5::trace {

std::string Range::text() const {
  if (all()) return "all";
  if (last == std::numeric_limits<std::int64_t>::max()) return fmt::format("{}:", first);
  return fmt::format("{}:{}", first, last);
}

namespace {

constexpr std::int64_t kMaxCoordinate = 1 << 30;

// Every number of a selection is checked against its width (common/checked_number.hpp):
// nothing wraps into another pixel or a negative size.
std::int64_t parse_int(const std::string& s, const std::string& what,
                       std::int64_t max = std::numeric_limits<std::int64_t>::max()) {
  try {
    return parse_integer<std::int64_t>(s, what, 0, max);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const auto k = s.find(sep, start);
    out.push_back(s.substr(start, k - start));
    if (k == std::string::npos) return out;
    start = k + 1;
  }
}

}  // namespace

Range parse_range(const std::string& text, const std::string& what) {
  Range r;
  const auto colon = text.find(':');
  if (colon == std::string::npos) {
    r.first = parse_int(text, what, std::numeric_limits<std::int64_t>::max() - 1);
    r.last = r.first + 1;
    return r;
  }
  const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
  if (!a.empty()) r.first = parse_int(a, what);
  if (!b.empty()) r.last = parse_int(b, what);
  if (r.last <= r.first) {
    throw std::runtime_error(
        fmt::format("{} '{}': empty range (expected A:B with A < B, A:, :B or N)", what,
                    escape_for_message(text)));
  }
  return r;
}

Rect parse_rect(const std::string& text, const std::string& what) {
  const auto parts = split(text, ',');
  if (parts.size() != 2 && parts.size() != 4) {
    throw std::runtime_error(
        fmt::format("{} '{}': expected X,Y or X,Y,WIDTH,HEIGHT", what, escape_for_message(text)));
  }
  // Coordinates and sizes fit in half an int, so that X + WIDTH cannot overflow; the screen
  // check then names the rectangle.
  Rect r;
  r.x = static_cast<int>(parse_int(parts[0], what + " X", kMaxCoordinate));
  r.y = static_cast<int>(parse_int(parts[1], what + " Y", kMaxCoordinate));
  if (parts.size() == 4) {
    r.width = static_cast<int>(parse_int(parts[2], what + " WIDTH", kMaxCoordinate));
    r.height = static_cast<int>(parse_int(parts[3], what + " HEIGHT", kMaxCoordinate));
    if (r.width < 1 || r.height < 1) {
      throw std::runtime_error(
          fmt::format("{} '{}': width and height must be >= 1", what, escape_for_message(text)));
    }
  }
  return r;
}

nlohmann::json Selection::to_json() const {
  nlohmann::json j;
  j["rects"] = nlohmann::json::array();
  for (const Rect& r : rects) j["rects"].push_back({r.x, r.y, r.width, r.height});
  j["regions"] = regions;
  j["fields"] = fields;
  j["instructions"] = instructions.text();
  j["primitives"] = primitives.text();
  j["frames"] = frames.text();
  return j;
}

nlohmann::json firmware_json(const Program& program, const std::vector<bool>& traced) {
  nlohmann::json f;
  f["name"] = program.name;
  f["memory_bits"] = program.memory_bits;
  f["staging_bits"] = program.staging_bits;
  f["fields"] = nlohmann::json::array();
  for (std::size_t i = 0; i < program.fields.size(); ++i) {
    const FieldDecl& d = program.fields[i];
    f["fields"].push_back({{"name", d.name},
                           {"lo", d.spilled ? -1 : d.lo},
                           {"width", d.width},
                           {"signed", d.is_signed},
                           {"spilled", d.spilled},
                           {"traced", i < traced.size() && traced[i]}});
  }
  f["outputs"] = nlohmann::json::array();
  for (const Field& o : program.outputs) {
    std::string name = "?";
    for (const FieldDecl& d : program.fields) {
      if (!d.spilled && d.lo == o.lo && d.width == o.width) name = d.name;
    }
    f["outputs"].push_back(name);
  }
  f["procedures"] = nlohmann::json::object();
  for (int p = 0; p < static_cast<int>(Procedure::count); ++p) {
    auto code = nlohmann::json::array();
    for (const Instruction& ins : program.procedures[p].code) {
      code.push_back({{"text", disassemble(ins)},
                      {"line", ins.line},
                      {"opcode", static_cast<int>(ins.op)},
                      {"mnemonic", instruction_info(ins.op).mnemonic}});
    }
    f["procedures"][kProcedureNames[p]] = code;
  }
  return f;
}

// The observer of one board. Only its own board's thread calls it.
class BoardRecorder : public BoardObserver {
 public:
  BoardRecorder(const Recorder& r, int renderer)
      : r_(r), renderer_(renderer), overhead_(r.config_.renderer.packet_overhead_cycles) {}

  void begin_packet(const PacketContext& p, const ProcedureCode&, const RendererBoard&) override {
    if (p.region != region_) {
      region_ = p.region;
      pixels_ = &r_.by_region_[static_cast<std::size_t>(p.region)];
      last_.assign(pixels_->size() * r_.fields_.size(), 0);
      synced_ = false;
      packet_number_ = 0;
    } else {
      ++packet_number_;
    }
    packet_ = p;
    cycle_ = p.start_cycle + overhead_;
    const bool primitive_ok = r_.selection_.primitives.all() ||
                              (p.primitive >= 0 && r_.selection_.primitives.contains(p.primitive));
    packet_in_window_ = primitive_ok && r_.selection_.frames.contains(r_.frame_);
  }

  void after_instruction(int index, const Instruction& ins, ArrayCycles cost,
                         const RendererBoard& board) override {
    const std::uint64_t seq = seq_++;
    const std::uint64_t start = cycle_;
    cycle_ += cost.count;
    if (pixels_ == nullptr || pixels_->empty()) return;
    if (!packet_in_window_ ||
        !r_.selection_.instructions.contains(static_cast<std::int64_t>(seq))) {
      synced_ = false;
      return;
    }
    const PixelBackend& array = board.array();
    InstructionRecord rec;
    rec.procedure = static_cast<std::uint8_t>(packet_.procedure);
    rec.flags = synced_ ? 0 : kFullState;
    rec.light = static_cast<std::uint8_t>(std::max(0, packet_.light));
    rec.renderer = static_cast<std::uint16_t>(renderer_);
    rec.index = static_cast<std::uint16_t>(index);
    rec.region = static_cast<std::uint32_t>(packet_.region);
    rec.primitive = packet_.primitive;
    rec.packet = packet_number_;
    rec.enabled = static_cast<std::uint32_t>(array.count_enabled());
    rec.cost = static_cast<std::uint32_t>(cost.count);
    rec.seq = seq;
    rec.cycle = start;
    append(out_, rec);
    ++count_;
    // The field the instruction writes (operand letter F), under Enable except for bsld.
    const bool writes = instruction_info(ins.op).operands[0] == 'F';
    const Field& dst = ins.operands[0].field;
    std::size_t k = 0;
    for (const auto& px : *pixels_) {
      const bool pixel_written = writes && (ins.op == Opcode::bsld || array.enabled(px.index));
      for (const auto& f : r_.fields_) {
        const std::uint64_t v = array.read(px.index, f.field);
        const bool written =
            pixel_written && dst.lo < f.field.lo + f.field.width && f.field.lo < dst.lo + dst.width;
        if (!synced_ || v != last_[k] || written) {
          last_[k] = v;
          append(out_,
                 ValueRecord{static_cast<std::uint16_t>(f.index), static_cast<std::uint16_t>(px.x),
                             static_cast<std::uint16_t>(px.y), v});
          ++count_;
        }
        ++k;
      }
    }
    synced_ = true;
  }

  void end_region(int, const RendererBoard&) override {}

  const std::vector<std::uint8_t>& out() const { return out_; }
  std::uint64_t count() const { return count_; }

 private:
  const Recorder& r_;
  int renderer_;
  std::uint64_t overhead_;
  std::vector<std::uint8_t> out_;
  std::uint64_t count_ = 0;
  std::uint64_t seq_ = 0;
  int region_ = -1;
  const std::vector<Recorder::PixelRef>* pixels_ = nullptr;
  std::vector<std::uint64_t> last_;
  bool synced_ = false;
  bool packet_in_window_ = false;
  PacketContext packet_;
  std::uint32_t packet_number_ = 0;
  std::uint64_t cycle_ = 0;
};

Recorder::Recorder(const MachineConfig& config, const Scene& scene, const Program& program,
                   const Selection& selection, int frame)
    : config_(config),
      program_(program),
      scene_name_(scene.name),
      scene_triangles_(scene.mesh.triangles.size()),
      selection_(selection),
      frame_(frame) {
  const int rw = config.renderer.region_width, rh = config.renderer.region_height;
  const int sw = config.screen.width, sh = config.screen.height;
  by_region_.resize(static_cast<std::size_t>(config.regions()));
  std::set<std::pair<int, int>> chosen;  // (y, x): row-major order
  for (const Rect& r : selection.rects) {
    if (r.x + r.width > sw || r.y + r.height > sh) {
      throw std::runtime_error(fmt::format(
          "--pixel/--rect {},{},{},{}: outside the {} x {} screen (pixels 0..{}, 0..{})", r.x, r.y,
          r.width, r.height, sw, sh, sw - 1, sh - 1));
    }
    for (int y = r.y; y < r.y + r.height; ++y) {
      for (int x = r.x; x < r.x + r.width; ++x) chosen.insert({y, x});
    }
  }
  for (int region : selection.regions) {
    if (region < 0 || region >= config.regions()) {
      throw std::runtime_error(
          fmt::format("--region {}: the screen has regions 0..{}", region, config.regions() - 1));
    }
    const int x0 = config.region_x0(region), y0 = config.region_y0(region);
    for (int y = y0; y < std::min(y0 + rh, sh); ++y) {
      for (int x = x0; x < std::min(x0 + rw, sw); ++x) chosen.insert({y, x});
    }
  }
  if (chosen.empty()) {
    throw std::runtime_error("trace: no pixels selected (give --pixel, --rect or --region)");
  }
  for (const auto& [y, x] : chosen) {
    const int region = (y / rh) * config.regions_x() + x / rw;
    by_region_[static_cast<std::size_t>(region)].push_back({(y % rh) * rw + x % rw, x, y});
    pixels_.emplace_back(x, y);
  }
  std::vector<std::string> names = selection.fields;
  if (names.empty()) {
    for (const FieldDecl& d : program.fields) {
      if (!d.spilled) names.push_back(d.name);
    }
  }
  std::vector<std::string> all;
  for (const FieldDecl& d : program.fields) all.push_back(d.name);
  for (const std::string& name : names) {
    const auto it = std::find(all.begin(), all.end(), name);
    if (it == all.end()) {
      throw std::runtime_error(fmt::format("--fields: '{}' is not a field of {} (fields: {})", name,
                                           program.name, fmt::join(all, " ")));
    }
    const auto i = static_cast<int>(it - all.begin());
    const FieldDecl& d = program.fields[static_cast<std::size_t>(i)];
    if (d.spilled) {
      throw std::runtime_error(fmt::format(
          "--fields: '{}' is spilled to the backing store; only fields in pixel memory can be "
          "traced",
          name));
    }
    if (std::none_of(fields_.begin(), fields_.end(),
                     [&](const TracedField& t) { return t.index == i; })) {
      fields_.push_back({i, Field{d.lo, d.width, d.is_signed}});
    }
  }
  boards_.resize(static_cast<std::size_t>(config.renderer.count));
}

Recorder::~Recorder() = default;

BoardObserver* Recorder::observer(int renderer) {
  auto& b = boards_.at(static_cast<std::size_t>(renderer));
  if (!b) b = std::make_unique<BoardRecorder>(*this, renderer);
  return b.get();
}

nlohmann::json Recorder::header() const {
  std::vector<bool> traced(program_.fields.size(), false);
  for (const auto& f : fields_) traced[static_cast<std::size_t>(f.index)] = true;
  nlohmann::json h;
  h["format"] = "pp5sim per-pixel trace";
  h["version"] = kTraceVersion;
  h["frame"] = frame_;
  h["scene"] = {{"name", scene_name_}, {"triangles", scene_triangles_}};
  h["config"] = config_.to_json();
  h["firmware"] = firmware_json(program_, traced);
  h["selection"] = selection_.to_json();
  h["pixels"] = pixels_;
  return h;
}

std::vector<std::uint8_t> Recorder::records(std::uint64_t& count) const {
  std::vector<std::uint8_t> out;
  count = 0;
  for (const auto& b : boards_) {
    if (!b) continue;
    out.insert(out.end(), b->out().begin(), b->out().end());
    count += b->count();
  }
  return out;
}

void Recorder::write(const std::string& path) const {
  std::uint64_t count = 0;
  const auto recs = records(count);
  write_trace(path, header(), recs, count);
}

}  // namespace pp5::trace
