#pragma once
// The fuzz targets as plain functions, so that the libFuzzer programs (fuzz_*.cpp, built with
// -DPP5_FUZZ=ON and clang) and the normal test suite (which replays every input kept in
// fuzz/regressions/) run exactly the same code.
//
// Contract of each target: any input either parses or throws the parser's own error type
// with a message; anything else (another exception, a crash, a sanitizer report, a hang,
// running out of memory) is a bug. The targets catch only the documented error types, so an
// unexpected std::exception escapes and libFuzzer reports it as a crash.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "firmware/assembler/assembler.hpp"
#include "models/config/machine_config.hpp"
#include "sim/scene/mesh_loader.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/scene/sphere_scenes.hpp"
#include "sim/trace/snapshot.hpp"
#include "sim/trace/trace_file.hpp"

namespace pp5::fuzz {

// Limits small enough that each input runs in milliseconds, so the fuzzer explores.
inline LoadLimits fuzz_limits() {
  LoadLimits limits;
  limits.max_vertices = 100'000;
  limits.max_triangles = 200'000;
  limits.max_polygon_vertices = 256;
  return limits;
}

// The first byte chooses the format, the rest is the file.
inline void mesh(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return;
  static const char* formats[] = {"obj", "off", "stl", "ply"};
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    parse_mesh(text, formats[data[0] % 4], "fuzz", nullptr, fuzz_limits());
  } catch (const MeshError&) {
  }
}

// Molecule files through gemmi: the first byte chooses PDB (even) or mmCIF (odd).
inline void molecule(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    parse_molecule(text, "fuzz", (data[0] & 1) != 0);
  } catch (const SceneError&) {
  }
}

inline void scene(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    // Mesh files resolve against a folder that does not exist, so they fail cleanly.
    parse_scene_json(text, "fuzz.json", "/nonexistent-pp5-fuzz", fuzz_limits());
  } catch (const SceneError&) {
  } catch (const MeshError&) {
  }
}

inline void config(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  // Lines starting with '=' are --set assignments; the rest is the JSON document.
  std::string doc;
  std::vector<std::string> sets;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(pos, end - pos);
    if (!line.empty() && line[0] == '=') {
      sets.push_back(line.substr(1));
    } else {
      doc += line + "\n";
    }
    pos = end + 1;
  }
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(doc);
  } catch (const nlohmann::json::exception&) {  // the file reader turns these into ConfigError
    return;
  }
  try {
    MachineConfig c = MachineConfig::from_json(j, "fuzz.json");
    c.set(sets);
    (void)c.to_json().dump();
  } catch (const ConfigError&) {
  }
}

inline void assembler(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const Program p = assemble(text, "fuzz.pp5", AssemblerOptions{});
    (void)listing(p, TimingParams{}, ParameterValues{}, "no scene");
  } catch (const AssemblyError&) {
  }
}

// A trace file's bytes (.pp5t): preamble, JSON header, records, checksum. An input that
// starts with '{' is framed here instead: the JSON header up to the first NUL, then a
// record count byte and the records; the target writes the preamble, lengths and checksum
// (encode_trace), so every input reaches the header's fields (their widths and ranges) and
// the records, rather than stopping at the checksum.
inline void trace(const std::uint8_t* data, std::size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (!bytes.empty() && bytes[0] == '{') {
    const std::size_t nul = std::min(bytes.find('\0'), bytes.size());
    const nlohmann::json header =
        nlohmann::json::parse(bytes.substr(0, nul), nullptr, /*allow_exceptions=*/false);
    if (header.is_discarded()) return;
    std::vector<std::uint8_t> records(bytes.begin() + static_cast<long>(std::min(nul + 1, size)),
                                      bytes.end());
    const std::uint64_t count = records.empty() ? 0 : records[0];
    if (!records.empty()) records.erase(records.begin());
    bytes = trace::encode_trace(header, records, count);
  }
  try {
    (void)trace::parse_trace(bytes, "fuzz.pp5t");
  } catch (const trace::TraceError&) {
  }
}

// A snapshot file's bytes (.pp5m); a snapshot that parses is also turned into a field image,
// which reads every field the header names. An input that starts with '{' is a header alone:
// the target adds planes of the size the header's geometry gives (when it is small) and the
// checksum (encode_snapshot), so every input reaches the header's fields.
inline void snapshot(const std::uint8_t* data, std::size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (!bytes.empty() && bytes[0] == '{') {
    trace::Snapshot s;
    s.header = nlohmann::json::parse(bytes, nullptr, /*allow_exceptions=*/false);
    if (s.header.is_discarded()) return;
    auto small = [&](const char* key) -> std::uint64_t {
      const auto* v = s.header.is_object() && s.header.contains(key)
                          ? s.header.at(key).get_ptr<const nlohmann::json::number_unsigned_t*>()
                          : nullptr;
      return v && *v <= 1024 ? *v : 0;
    };
    const std::uint64_t words = small("memory_bits") * small("width") * small("height") / 64;
    if (words <= (1u << 17)) s.planes.assign(words, 0x5555aaaa5555aaaaull);
    bytes = trace::encode_snapshot(s);
  }
  try {
    const trace::Snapshot s = trace::parse_snapshot(bytes, "fuzz.pp5m");
    for (const auto& f : s.header.at("firmware").at("fields")) {
      if (f.at("lo").get<int>() >= 0) (void)trace::field_image(s, f.at("name").get<std::string>());
    }
  } catch (const trace::TraceError&) {
  }
}

// A scene file's "csg" expression: the input is the expression's JSON, set in a scene of
// four one-triangle meshes named a, b, c and d; normalisation (sim/scene/csg_expression.hpp)
// must stay within its bounds however the operators nest.
inline void csg(const std::uint8_t* data, std::size_t size) {
  const std::string expression(reinterpret_cast<const char*>(data), size);
  std::string text = R"({"meshes": [)";
  for (const char* name : {"a", "b", "c", "d"}) {
    text += std::string(name[0] == 'a' ? "" : ",") + R"({"name": ")" + name +
            R"(", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 2]]})";
  }
  text += R"(], "csg": )" + expression + "}";
  try {
    parse_scene_json(text, "fuzz.json", "/nonexistent-pp5-fuzz", fuzz_limits());
  } catch (const SceneError&) {
  } catch (const MeshError&) {
  }
}

}  // namespace pp5::fuzz
