#include "sim/trace/snapshot.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

#include "common/checked_number.hpp"
#include "common/escape.hpp"
#include "common/read_file.hpp"
#include "common/strict_json.hpp"
#include "sim/simulation.hpp"
#include "sim/trace/recorder.hpp"
#include "sim/trace/trace_file.hpp"

namespace pp5::trace {

namespace {
constexpr char kSnapMagic[8] = {'P', 'P', '5', 'S', 'N', 'A', 'P', 0};
constexpr std::uint32_t kSnapVersion = 1;

void put64(std::string& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
}
void put32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
}
std::uint64_t get(const std::uint8_t* p, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}
}  // namespace

std::uint64_t Snapshot::read(int pixel, int lo, int w) const {
  std::uint64_t v = 0;
  const int word = pixel / 64, bit = pixel % 64;
  for (int b = 0; b < w; ++b) {
    const std::uint64_t plane_word = planes[static_cast<std::size_t>(lo + b) * words() + word];
    v |= ((plane_word >> bit) & 1) << b;
  }
  return v;
}

class SnapshotTaker::Board : public BoardObserver {
 public:
  explicit Board(SnapshotTaker& t) : t_(t) {}
  void begin_packet(const PacketContext& p, const ProcedureCode&, const RendererBoard&) override {
    in_region_ = p.region == t_.region_;
  }
  void after_instruction(int, const Instruction&, ArrayCycles, const RendererBoard& b) override {
    const std::uint64_t seq = seq_++;
    if (!in_region_) return;
    if (!t_.ran_) t_.first_seq_ = seq;
    t_.ran_ = true;
    t_.last_seq_ = seq;
    if (t_.after_ && *t_.after_ == seq) take(b);
  }
  void end_region(int region, const RendererBoard& b) override {
    if (region == t_.region_ && !t_.after_) take(b);
  }

 private:
  void take(const RendererBoard& b) {
    const PixelBackend& a = b.array();
    Snapshot& s = t_.snap_;
    s.width = a.width();
    s.height = a.height();
    s.memory_bits = a.geometry().memory_bits;
    a.read_memory_planes(s.planes);
    t_.taken_ = true;
  }
  SnapshotTaker& t_;
  std::uint64_t seq_ = 0;
  bool in_region_ = false;
};

SnapshotTaker::SnapshotTaker(const MachineConfig& config, const Program& program, int region,
                             std::optional<std::uint64_t> after)
    : config_(config), program_(program), region_(region), after_(after) {
  if (region < 0 || region >= config.regions()) {
    throw std::runtime_error(
        fmt::format("--region {}: the screen has regions 0..{}", region, config.regions() - 1));
  }
}

SnapshotTaker::~SnapshotTaker() = default;

BoardObserver* SnapshotTaker::observer(int renderer) {
  if (renderer != region_ % config_.renderer.count) return nullptr;
  board_ = std::make_unique<Board>(*this);
  return board_.get();
}

const Snapshot& SnapshotTaker::snapshot() const {
  if (!taken_) {
    throw std::runtime_error(fmt::format(
        "--after {}: region {} ran micro-instructions {}..{} of renderer {}; choose one of those",
        after_ ? *after_ : 0, region_, first_seq_, last_seq_, region_ % config_.renderer.count));
  }
  Snapshot& s = const_cast<Snapshot&>(snap_);
  s.region = region_;
  s.header["format"] = "pp5sim pixel-memory snapshot";
  s.header["version"] = kSnapVersion;
  s.header["config"] = config_.to_json();
  std::vector<bool> traced(program_.fields.size(), true);
  s.header["firmware"] = firmware_json(program_, traced);
  s.header["region"] = region_;
  s.header["x0"] = config_.region_x0(region_);
  s.header["y0"] = config_.region_y0(region_);
  s.header["width"] = s.width;
  s.header["height"] = s.height;
  s.header["memory_bits"] = s.memory_bits;
  s.point = after_ ? fmt::format("after micro-instruction {} of renderer {}", *after_,
                                 region_ % config_.renderer.count)
                   : std::string("end of region");
  s.header["point"] = s.point;
  s.header["layout"] =
      "memory_bits bit-planes; plane b holds bit b of every pixel, pixel p = y * width + x at "
      "bit p % 64 of little-endian 64-bit word p / 64";
  return snap_;
}

void write_snapshot(const std::string& path, const Snapshot& s) {
  write_file_atomically(path, encode_snapshot(s));
}

std::string encode_snapshot(const Snapshot& s) {
  const std::string h = s.header.dump();
  std::string out(kSnapMagic, 8);
  put32(out, kSnapVersion);
  put32(out, static_cast<std::uint32_t>(h.size()));
  out += h;
  put64(out, static_cast<std::uint64_t>(s.planes.size()) * 8);
  for (std::uint64_t w : s.planes) put64(out, w);
  put64(out, fnv1a(reinterpret_cast<const std::uint8_t*>(out.data()), out.size()));
  return out;
}

Snapshot read_snapshot(const std::string& path) {
  std::string bytes;
  try {
    // The largest region (1024 x 1024 pixels of 1024 bits) is 128 MiB of planes.
    bytes = read_regular_file(path, (128ull << 20) + (1ull << 20), "a pp5sim snapshot");
  } catch (const FileError& e) {
    throw TraceError(e.what());
  }
  return parse_snapshot(bytes, path);
}

Snapshot parse_snapshot(const std::string& bytes, const std::string& path) {
  const auto* d = reinterpret_cast<const std::uint8_t*>(bytes.data());
  const std::size_t n = bytes.size();
  if (n < 8 || std::memcmp(d, kSnapMagic, 8) != 0) {
    throw TraceError(fmt::format("{}: not a pp5sim snapshot (no 'PP5SNAP' magic)", path));
  }
  if (n < 16) throw TraceError(fmt::format("{}: truncated at byte {}, expected 16", path, n));
  if (get(d + 8, 4) != kSnapVersion) {
    throw TraceError(
        fmt::format("{}: snapshot version {}, expected {}", path, get(d + 8, 4), kSnapVersion));
  }
  const std::size_t hl = get(d + 12, 4);
  if (n < 16 + hl + 8) {
    throw TraceError(fmt::format("{}: truncated at byte {}, expected {}", path, n, 16 + hl + 8));
  }
  const std::uint64_t payload = get(d + 16 + hl, 8);
  const std::size_t at = 16 + hl + 8;
  if (payload > n || n - at != payload + 8 || payload % 8) {
    throw TraceError(fmt::format("{}: truncated or padded at byte {}, expected {} bytes", path, n,
                                 at + std::min<std::uint64_t>(payload, n) + 8));
  }
  if (get(d + at + payload, 8) != fnv1a(d, at + payload)) {
    throw TraceError(
        fmt::format("{}: checksum mismatch at byte {}: the file is corrupted", path, at + payload));
  }
  Snapshot s;
  try {
    try {
      s.header = parse_strict_json(
          std::string(bytes.begin() + 16, bytes.begin() + 16 + static_cast<long>(hl)),
          path + ": header at byte 16");
    } catch (const std::runtime_error& e) {
      throw TraceError(e.what());
    }
    if (!s.header.is_object()) {
      throw TraceError(fmt::format("{}: header at byte 16: a JSON object expected", path));
    }
    // Each number checked against its width (common/checked_number.hpp): a forged
    // 2^32 + 64 is refused, never read as 64.
    auto integer = [&](const char* key, int min, int max) {
      try {
        return json_integer<int>(s.header.at(key), std::string("header: ") + key, min, max);
      } catch (const std::invalid_argument& e) {
        throw TraceError(fmt::format("{}: {}", path, e.what()));
      }
    };
    const nlohmann::json& point = s.header.at("point");
    if (!point.is_string() || point.get_ref<const std::string&>().size() > 256 ||
        !is_display_text(point.get_ref<const std::string&>())) {
      throw TraceError(fmt::format(
          "{}: header: point = {}: expected text of at most 256 bytes without control characters",
          path,
          escape_for_message(
              point.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace))));
    }
    s.point = point.get<std::string>();
    s.region = integer("region", 0, std::numeric_limits<int>::max());
    s.width = integer("width", 64, 1024);
    s.height = integer("height", 1, 1024);
    s.memory_bits = integer("memory_bits", 1, 1024);
  } catch (const nlohmann::json::exception& e) {
    throw TraceError(fmt::format("{}: bad header at byte 16: {}", path, json_error_text(e)));
  }
  // The header's meaning, not only its bytes: a forged header (with its checksum
  // recomputed) must not make a reader index past the planes.
  if (s.width < 64 || s.width > 1024 || s.width % 64 || s.height < 1 || s.height > 1024 ||
      s.memory_bits < 1 || s.memory_bits > 1024) {
    throw TraceError(fmt::format(
        "{}: header at byte 16: a {} x {} region of {} bits is outside what a Renderer can be "
        "(width 64..1024 in steps of 64, height 1..1024, 1..1024 bits)",
        path, s.width, s.height, s.memory_bits));
  }
  if (payload != static_cast<std::uint64_t>(s.memory_bits) * s.words() * 8) {
    throw TraceError(
        fmt::format("{}: header's geometry does not match the {} bytes of planes", path, payload));
  }
  try {
    const nlohmann::json& fields = s.header.at("firmware").at("fields");
    if (!fields.is_array())
      throw TraceError(fmt::format("{}: 'firmware.fields' is not a list", path));
    for (std::size_t k = 0; k < fields.size(); ++k) {
      const nlohmann::json& f = fields[k];
      const std::string name = f.at("name").get<std::string>();
      const std::string what = fmt::format("header: field {} ('{}')", k, escape_for_message(name));
      if (name.empty() || name.size() > 64 || !is_display_text(name)) {
        throw TraceError(fmt::format(
            "{}: {}: a field's name is text of 1 to 64 bytes without control characters", path,
            what));
      }
      int lo = 0, width = 0;
      try {
        lo = json_integer<int>(f.at("lo"), what + " lo", -1, s.memory_bits - 1);
        width = json_integer<int>(f.at("width"), what + " width", 1, 64);
      } catch (const std::invalid_argument& e) {
        throw TraceError(fmt::format("{}: {}", path, e.what()));
      }
      f.at("signed").get<bool>();
      if (width < 1 || width > 64 || lo < -1 || (lo >= 0 && lo + width > s.memory_bits)) {
        throw TraceError(fmt::format(
            "{}: header's field {} ('{}') has bits [{}, {}), outside the {} bits of pixel memory "
            "(and a field is 1..64 bits wide; lo -1 marks a spilled field)",
            path, k, escape_for_message(name), lo, lo + width, s.memory_bits));
      }
    }
  } catch (const nlohmann::json::exception& e) {
    throw TraceError(fmt::format("{}: bad field map in the header: {}", path, json_error_text(e)));
  }
  s.planes.resize(payload / 8);
  for (std::size_t i = 0; i < s.planes.size(); ++i) s.planes[i] = get(d + at + 8 * i, 8);
  return s;
}

RgbImage field_image(const Snapshot& s, const std::string& name) {
  const nlohmann::json* field = nullptr;
  std::vector<std::string> names;
  for (const auto& f : s.header.at("firmware").at("fields")) {
    names.push_back(f.at("name"));
    if (f.at("name") == name) field = &f;
  }
  if (!field) {
    throw std::runtime_error(
        fmt::format("--png {}: no such field (fields: {})", name, fmt::join(names, " ")));
  }
  const int lo = field->at("lo"), width = field->at("width");
  const bool is_signed = field->at("signed");
  if (lo < 0) throw std::runtime_error(fmt::format("--png {}: field is spilled", name));
  const int n = s.width * s.height;
  std::vector<std::int64_t> v(static_cast<std::size_t>(n));
  for (int p = 0; p < n; ++p) {
    std::uint64_t raw = s.read(p, lo, std::min(width, 64));
    if (is_signed && width < 64 && ((raw >> (width - 1)) & 1)) raw |= ~std::uint64_t{0} << width;
    v[static_cast<std::size_t>(p)] = static_cast<std::int64_t>(raw);
  }
  const auto [mn, mx] = std::minmax_element(v.begin(), v.end());
  RgbImage img;
  img.width = s.width;
  img.height = s.height;
  img.rgb.resize(static_cast<std::size_t>(n) * 3);
  for (int p = 0; p < n; ++p) {
    std::uint8_t g;
    if (width == 1) {
      g = v[static_cast<std::size_t>(p)] ? 255 : 0;
    } else if (*mx == *mn) {
      g = 0;
    } else {
      g = static_cast<std::uint8_t>(
          std::llround(255.0 * static_cast<double>(v[static_cast<std::size_t>(p)] - *mn) /
                       static_cast<double>(*mx - *mn)));
    }
    for (int c = 0; c < 3; ++c) img.rgb[static_cast<std::size_t>(p) * 3 + c] = g;
  }
  return img;
}

}  // namespace pp5::trace
