#pragma once
// The per-pixel trace file (.pp5t): format, writer and validating reader. The format is
// documented byte by byte in traces/README.md.
//
// Contract: read_trace() either returns a trace whose every record is in range (field
// indices, procedures, instruction indices, value records after an instruction record) or
// throws TraceError with "FILE: what is wrong at byte N"; it never reads past the data it
// has checked, so truncated or corrupted files cannot crash it.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace pp5::trace {

struct TraceError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline constexpr char kTraceMagic[8] = {'P', 'P', '5', 'T', 'R', 'A', 'C', 'E'};
inline constexpr std::uint32_t kTraceVersion = 1;
inline constexpr std::size_t kPreambleBytes = 16;  // magic, version, header length

enum RecordKind : std::uint8_t { kInstructionRecord = 1, kValueRecord = 2 };
inline constexpr std::size_t kInstructionRecordBytes = 44;
inline constexpr std::size_t kValueRecordBytes = 16;
// Flag of an instruction record: its value records give the whole selected state of the
// pixels (the first instruction of a window), not only what the instruction changed.
inline constexpr std::uint8_t kFullState = 1;

// One executed micro-instruction of a region that holds selected pixels.
struct InstructionRecord {
  std::uint8_t procedure = 0;  // Procedure: clear, triangle, pass, shade, light
  std::uint8_t flags = 0;
  std::uint8_t light = 0;  // the scene light of a `light` instruction, else 0
  std::uint16_t renderer = 0;
  std::uint16_t index = 0;  // instruction's index in its procedure (header: text, line)
  std::uint32_t region = 0;
  std::int32_t primitive = -1;  // scene triangle, -1 for the other procedures
  std::uint32_t packet = 0;     // packet number within the region: 0 = clear, then triangles
  std::uint32_t enabled = 0;    // pixels with Enable = 1 after the instruction
  std::uint32_t cost = 0;       // array cycles
  std::uint64_t seq = 0;        // micro-instruction number on its Renderer, from 0
  std::uint64_t cycle = 0;      // simulated array cycle at which it started
};

// A selected field's new value in one selected pixel, after the preceding instruction.
struct ValueRecord {
  std::uint16_t field = 0;  // index in header.firmware.fields
  std::uint16_t x = 0, y = 0;
  std::uint64_t value = 0;  // raw bits, zero-extended
};

// What a record's packet was: "triangle N", "light K", or the procedure's name.
std::string packet_label(const InstructionRecord& r);

// Appends records in the file's encoding (little-endian).
void append(std::vector<std::uint8_t>& out, const InstructionRecord& r);
void append(std::vector<std::uint8_t>& out, const ValueRecord& r);

// Writes magic, version, header, records and checksum, through a temporary file.
void write_trace(const std::string& path, const nlohmann::json& header,
                 const std::vector<std::uint8_t>& records, std::uint64_t record_count);
std::string encode_trace(const nlohmann::json& header, const std::vector<std::uint8_t>& records,
                         std::uint64_t record_count);

struct FieldInfo {
  std::string name;
  int lo = -1;
  int width = 0;
  bool is_signed = false;
  bool traced = false;
};

struct InstructionText {
  std::string text;  // checked: printable text of at most kMaxInstructionText bytes
  int line = 0;
  int opcode = 0;  // 0..255
};

struct Event {
  InstructionRecord ins;
  std::size_t first_value = 0;  // index into Trace::values
  std::size_t value_count = 0;
};

struct Value {
  ValueRecord rec;
  std::size_t event = 0;  // index into Trace::events
};

// Header strings are shown to the user: each is text of at most this many bytes, without
// control characters (a forged header cannot drive the terminal or bloat a VCD).
inline constexpr std::size_t kMaxHeaderText = 256;
inline constexpr std::size_t kMaxInstructionText = 1000;

struct Trace {
  std::string path;
  nlohmann::json header;  // as read (trace info prints it); the fields below are checked
  std::string scene_name;
  std::string firmware_name;
  std::vector<std::string> outputs;  // the firmware's output fields, "?" for an unnamed one
  int memory_bits = 0;
  double clock_hz = 0;  // the Renderer's array clock, for the VCD's time scale
  std::vector<FieldInfo> fields;
  std::vector<std::vector<InstructionText>> procedures;  // [procedure][index]
  std::vector<std::pair<int, int>> pixels;               // selected screen pixels
  std::vector<Event> events;
  std::vector<Value> values;

  const InstructionText& text(const InstructionRecord& r) const {
    return procedures[r.procedure][r.index];
  }
  int field_index(const std::string& name) const;              // -1 if absent
  std::int64_t as_number(int field, std::uint64_t raw) const;  // signed fields sign-extended
};

Trace read_trace(const std::string& path);
Trace parse_trace(const std::string& bytes, const std::string& name);

// FNV-1a, 64 bits: the trailer of trace and snapshot files.
std::uint64_t fnv1a(const std::uint8_t* data, std::size_t n);

}  // namespace pp5::trace
