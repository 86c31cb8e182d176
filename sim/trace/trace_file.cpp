#include "sim/trace/trace_file.hpp"

#include <fmt/format.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>

#include "common/checked_number.hpp"
#include "common/escape.hpp"
#include "common/read_file.hpp"
#include "common/strict_json.hpp"
#include "firmware/isa/interface.hpp"
#include "sim/simulation.hpp"

namespace pp5::trace {

namespace {

template <typename T>
void put(std::vector<std::uint8_t>& out, T v) {
  using U = std::make_unsigned_t<T>;
  const auto u = static_cast<U>(v);
  for (std::size_t i = 0; i < sizeof(T); ++i)
    out.push_back(static_cast<std::uint8_t>(u >> (8 * i)));
}

template <typename T>
T get(const std::uint8_t* p) {
  using U = std::make_unsigned_t<T>;
  U u = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) u |= static_cast<U>(static_cast<U>(p[i]) << (8 * i));
  return static_cast<T>(u);
}

}  // namespace

std::uint64_t fnv1a(const std::uint8_t* data, std::size_t n) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= data[i];
    h *= 0x100000001b3ull;
  }
  return h;
}

std::string packet_label(const InstructionRecord& r) {
  if (r.primitive >= 0) return fmt::format("triangle {}", r.primitive);
  if (r.procedure == static_cast<int>(Procedure::light)) return fmt::format("light {}", r.light);
  return kProcedureNames[r.procedure];
}

void append(std::vector<std::uint8_t>& out, const InstructionRecord& r) {
  put<std::uint8_t>(out, kInstructionRecord);
  put(out, r.procedure);
  put(out, r.flags);
  put(out, r.light);
  put(out, r.renderer);
  put(out, r.index);
  put(out, r.region);
  put(out, r.primitive);
  put(out, r.packet);
  put(out, r.enabled);
  put(out, r.cost);
  put(out, r.seq);
  put(out, r.cycle);
}

void append(std::vector<std::uint8_t>& out, const ValueRecord& r) {
  put<std::uint8_t>(out, kValueRecord);
  put<std::uint8_t>(out, 0);
  put(out, r.field);
  put(out, r.x);
  put(out, r.y);
  put(out, r.value);
}

std::string encode_trace(const nlohmann::json& header, const std::vector<std::uint8_t>& records,
                         std::uint64_t record_count) {
  const std::string h = header.dump();
  std::vector<std::uint8_t> out(kTraceMagic, kTraceMagic + 8);
  put(out, kTraceVersion);
  put(out, static_cast<std::uint32_t>(h.size()));
  out.insert(out.end(), h.begin(), h.end());
  put(out, record_count);
  put(out, static_cast<std::uint64_t>(records.size()));
  out.insert(out.end(), records.begin(), records.end());
  put(out, fnv1a(out.data(), out.size()));
  return std::string(out.begin(), out.end());
}

void write_trace(const std::string& path, const nlohmann::json& header,
                 const std::vector<std::uint8_t>& records, std::uint64_t record_count) {
  write_file_atomically(path, encode_trace(header, records, record_count));
}

int Trace::field_index(const std::string& name) const {
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (fields[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

std::int64_t Trace::as_number(int field, std::uint64_t raw) const {
  const FieldInfo& f = fields[field];
  if (f.is_signed && f.width > 0 && f.width < 64 && ((raw >> (f.width - 1)) & 1)) {
    return static_cast<std::int64_t>(raw | (~std::uint64_t{0} << f.width));
  }
  return static_cast<std::int64_t>(raw);
}

Trace read_trace(const std::string& path) {
  std::string bytes;
  try {
    // Read whole: a trace larger than 4 GiB is to be windowed when recorded (--after,
    // --before, fewer pixels), not loaded.
    bytes = read_regular_file(path, 4ull << 30, "a pp5sim trace");
  } catch (const FileError& e) {
    throw TraceError(e.what());
  }
  return parse_trace(bytes, path);
}

Trace parse_trace(const std::string& bytes, const std::string& name) {
  const auto* d = reinterpret_cast<const std::uint8_t*>(bytes.data());
  const std::size_t n = bytes.size();
  auto truncated = [&](std::size_t need, const char* what) {
    return TraceError(fmt::format("{}: truncated at byte {}, expected {} ({} bytes in all)", name,
                                  n, what, need));
  };
  if (n < 8 || std::memcmp(d, kTraceMagic, 8) != 0) {
    if (n < 8 && std::memcmp(d, kTraceMagic, n) == 0) throw truncated(8, "the magic 'PP5TRACE'");
    throw TraceError(
        fmt::format("{}: not a pp5sim trace (the file does not start with 'PP5TRACE')", name));
  }
  if (n < kPreambleBytes) throw truncated(kPreambleBytes, "the version and header length");
  const auto version = get<std::uint32_t>(d + 8);
  if (version != kTraceVersion) {
    throw TraceError(fmt::format("{}: trace format version {}, this pp5sim reads version {}", name,
                                 version, kTraceVersion));
  }
  const std::size_t header_len = get<std::uint32_t>(d + 12);
  const std::size_t header_end = kPreambleBytes + header_len;
  if (n < header_end + 16) throw truncated(header_end + 16, "the JSON header and record counts");
  const std::uint64_t record_count = get<std::uint64_t>(d + header_end);
  const std::uint64_t record_bytes = get<std::uint64_t>(d + header_end + 8);
  const std::size_t records_at = header_end + 16;
  if (record_bytes > n || n - records_at < record_bytes + 8) {
    if (record_bytes <= n && n - records_at < record_bytes + 8) {
      throw truncated(records_at + record_bytes + 8, "the records and the checksum");
    }
    throw TraceError(fmt::format("{}: byte {}: record section of {} bytes is longer than the file",
                                 name, header_end + 8, record_bytes));
  }
  const std::size_t checksum_at = records_at + record_bytes;
  if (n > checksum_at + 8) {
    throw TraceError(fmt::format("{}: {} unexpected bytes after the checksum at byte {}", name,
                                 n - checksum_at - 8, checksum_at));
  }
  const std::uint64_t stored = get<std::uint64_t>(d + checksum_at);
  const std::uint64_t computed = fnv1a(d, checksum_at);
  if (stored != computed) {
    throw TraceError(
        fmt::format("{}: checksum mismatch at byte {} (stored {:016x}, computed {:016x}): the file "
                    "is corrupted",
                    name, checksum_at, stored, computed));
  }

  Trace t;
  t.path = name;
  try {
    // Strictly, like every JSON pp5sim reads: nesting bounded, a key given twice refused.
    try {
      t.header =
          parse_strict_json(std::string(bytes.begin() + kPreambleBytes, bytes.begin() + header_end),
                            fmt::format("{}: header at byte {}", name, kPreambleBytes));
    } catch (const std::runtime_error& e) {
      throw TraceError(e.what());
    }
    if (!t.header.is_object()) {
      throw TraceError(fmt::format("{}: header at byte {}: a JSON object expected (got {})", name,
                                   kPreambleBytes, t.header.type_name()));
    }
    // The field map's meaning, not only its syntax: a forged header (checksum recomputed)
    // must not make a reader shift or index out of range.
    // Every number is checked against its width (common/checked_number.hpp): a forged
    // 2^32 + 5 is refused, never read as 5.
    auto integer = [&](const nlohmann::json& v, const std::string& what, int min, int max) {
      try {
        return json_integer<int>(v, "header: " + what, min, max);
      } catch (const std::invalid_argument& e) {
        throw TraceError(fmt::format("{}: {}", name, e.what()));
      }
    };
    // Every string a report shows: text without control characters, of bounded length.
    auto text = [&](const nlohmann::json& v, const std::string& what, std::size_t max) {
      const bool ok = v.is_string() && v.get_ref<const std::string&>().size() <= max &&
                      is_display_text(v.get_ref<const std::string&>());
      if (!ok) {
        throw TraceError(fmt::format(
            "{}: header: {} = {}: expected text of at most {} bytes without control characters",
            name, what,
            escape_for_message(v.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)),
            max));
      }
      return v.get<std::string>();
    };
    const nlohmann::json& firmware = t.header.at("firmware");
    t.scene_name = text(t.header.at("scene").at("name"), "scene.name", kMaxHeaderText);
    t.firmware_name = text(firmware.at("name"), "firmware.name", kMaxHeaderText);
    // The array clock sets the VCD's time scale (picoseconds per cycle): the configuration
    // table's range for renderer.clock_hz.
    {
      const nlohmann::json& hz = t.header.at("config").at("renderer").at("clock_hz");
      t.clock_hz = hz.is_number() ? hz.get<double>() : 0.0;
      if (!(t.clock_hz >= 1e6 && t.clock_hz <= 1e9)) {
        throw TraceError(fmt::format(
            "{}: header: config.renderer.clock_hz = {}: expected a number from 1e6 to 1e9 (Hz)",
            name, escape_for_message(hz.dump())));
      }
    }
    const int memory_bits = integer(firmware.at("memory_bits"), "firmware.memory_bits", 1, 1024);
    t.memory_bits = memory_bits;
    for (const auto& f : firmware.at("fields")) {
      const std::string field_name = text(f.at("name"), "a field's name", 64);
      const std::string what = "field '" + escape_for_message(field_name) + "'";
      t.fields.push_back({field_name, integer(f.at("lo"), what + " lo", -1, memory_bits - 1),
                          integer(f.at("width"), what + " width", 1, 64),
                          f.at("signed").get<bool>(), f.at("traced").get<bool>()});
      const FieldInfo& fi = t.fields.back();
      if (fi.lo >= 0 && fi.lo + fi.width > memory_bits) {
        throw TraceError(fmt::format(
            "{}: header: field '{}' has bits [{}, {}), outside the {} bits of pixel memory (a "
            "field is 1..64 bits wide; lo -1 marks a spilled field)",
            name, escape_for_message(fi.name), fi.lo, fi.lo + fi.width, memory_bits));
      }
    }
    for (int p = 0; p < static_cast<int>(Procedure::count); ++p) {
      std::vector<InstructionText> code;
      // Traces written before the `light` procedure existed do not list it.
      const auto& procedures = firmware.at("procedures");
      if (!procedures.contains(kProcedureNames[p])) {
        t.procedures.emplace_back();
        continue;
      }
      for (const auto& i : procedures.at(kProcedureNames[p])) {
        const std::string where =
            fmt::format("instruction {} of procedure {}", code.size(), kProcedureNames[p]);
        code.push_back({text(i.at("text"), where + ": text", kMaxInstructionText),
                        integer(i.at("line"), where + ": line", 0, std::numeric_limits<int>::max()),
                        integer(i.at("opcode"), where + ": opcode", 0, 255)});
      }
      t.procedures.push_back(std::move(code));
    }
    for (const auto& o : firmware.at("outputs")) {
      t.outputs.push_back(text(o, "an output field's name", 64));
    }
    // Value records hold a pixel's x and y in 16 bits.
    for (const auto& p : t.header.at("pixels")) {
      t.pixels.emplace_back(integer(p.at(0), "pixel x", 0, 65535),
                            integer(p.at(1), "pixel y", 0, 65535));
    }
  } catch (const nlohmann::json::exception& e) {
    throw TraceError(
        fmt::format("{}: bad header at byte {}: {}", name, kPreambleBytes, json_error_text(e)));
  }

  const std::set<std::pair<int, int>> selected(t.pixels.begin(), t.pixels.end());
  std::size_t at = records_at;
  for (std::uint64_t k = 0; k < record_count; ++k) {
    if (at >= checksum_at) {
      throw TraceError(fmt::format("{}: byte {}: record {} of {} lies past the record section",
                                   name, at, k, record_count));
    }
    const std::uint8_t kind = d[at];
    const std::size_t size = kind == kInstructionRecord ? kInstructionRecordBytes
                             : kind == kValueRecord     ? kValueRecordBytes
                                                        : 0;
    if (size == 0) {
      throw TraceError(fmt::format("{}: byte {}: unknown record kind {}", name, at, kind));
    }
    if (checksum_at - at < size) {
      throw TraceError(
          fmt::format("{}: byte {}: record {} runs past the record section", name, at, k));
    }
    const std::uint8_t* r = d + at;
    if (kind == kInstructionRecord) {
      InstructionRecord i;
      i.procedure = r[1];
      i.flags = r[2];
      i.light = r[3];
      i.renderer = get<std::uint16_t>(r + 4);
      i.index = get<std::uint16_t>(r + 6);
      i.region = get<std::uint32_t>(r + 8);
      i.primitive = get<std::int32_t>(r + 12);
      i.packet = get<std::uint32_t>(r + 16);
      i.enabled = get<std::uint32_t>(r + 20);
      i.cost = get<std::uint32_t>(r + 24);
      i.seq = get<std::uint64_t>(r + 28);
      i.cycle = get<std::uint64_t>(r + 36);
      if (i.procedure >= t.procedures.size() || i.index >= t.procedures[i.procedure].size()) {
        throw TraceError(
            fmt::format("{}: byte {}: instruction {} of procedure {} is not in the "
                        "header's firmware",
                        name, at, i.index, i.procedure));
      }
      t.events.push_back({i, t.values.size(), 0});
    } else {
      ValueRecord v;
      v.field = get<std::uint16_t>(r + 2);
      v.x = get<std::uint16_t>(r + 4);
      v.y = get<std::uint16_t>(r + 6);
      v.value = get<std::uint64_t>(r + 8);
      if (t.events.empty()) {
        throw TraceError(
            fmt::format("{}: byte {}: value record before any instruction record", name, at));
      }
      if (v.field >= t.fields.size() || !t.fields[v.field].traced) {
        throw TraceError(fmt::format("{}: byte {}: value record names field {}, not a traced field",
                                     name, at, v.field));
      }
      if (!selected.count({v.x, v.y})) {
        throw TraceError(
            fmt::format("{}: byte {}: value record for pixel {},{}, which the header "
                        "does not list as selected",
                        name, at, v.x, v.y));
      }
      t.values.push_back({v, t.events.size() - 1});
      ++t.events.back().value_count;
    }
    at += size;
  }
  if (at != checksum_at) {
    throw TraceError(
        fmt::format("{}: byte {}: {} bytes left after the {} records the header "
                    "announced",
                    name, at, checksum_at - at, record_count));
  }
  return t;
}

}  // namespace pp5::trace
