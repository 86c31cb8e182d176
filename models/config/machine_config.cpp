#include "models/config/machine_config.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <variant>

namespace pp5 {

namespace {

using Ref = std::variant<int*, double*, std::string*>;

struct Parameter {
  const char* key;
  const char* unit;
  const char* confidence;
  double default_value;
  double min;
  double max;
  const char* description;
  Ref (*ref)(MachineConfig&);
  // Text parameters: the allowed values separated by '|', the first being the default.
  const char* choices = nullptr;
};

std::vector<std::string> split_choices(const char* choices) {
  std::vector<std::string> out;
  std::string cur;
  for (const char* c = choices; *c; ++c) {
    if (*c == '|') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += *c;
    }
  }
  out.push_back(cur);
  return out;
}

// The single declaration of every machine parameter. Confidence: P = the 1989 SIGGRAPH
// paper, S = a secondary source, A = an assumption of this simulator (see
// ../shared/design/pixel-planes-5.md for the sources).
const std::vector<Parameter>& parameter_table() {
  static const std::vector<Parameter> table = {
      {"screen.width", "pixels", "P", 1280, 64, 8192,
       "Width of the frame; the paper's frame buffer is 1280 x 1024.",
       [](MachineConfig& c) -> Ref { return &c.screen.width; }},
      {"screen.height", "pixels", "P", 1024, 1, 8192, "Height of the frame.",
       [](MachineConfig& c) -> Ref { return &c.screen.height; }},

      {"gp.count", "processors", "P", 32, 1, 64,
       "Graphics Processors (Intel i860); the paper's machine has up to 32.",
       [](MachineConfig& c) -> Ref { return &c.gp.count; }},
      {"gp.clock_hz", "Hz", "S", 40e6, 1e6, 1e9, "i860 clock.",
       [](MachineConfig& c) -> Ref { return &c.gp.clock_hz; }},
      {"gp.subpixel_bits", "bits", "A", 4, 0, 8,
       "Vertex positions are snapped to 1/2^n pixel before edge set-up, so that edge "
       "coefficients are exact integers and shared edges own each pixel exactly once.",
       [](MachineConfig& c) -> Ref { return &c.gp.subpixel_bits; }},
      {"gp.depth_bits", "bits", "A", 24, 8, 32,
       "Range of the depth expression: 0 at the near plane to 2^n - 1 at the far plane.",
       [](MachineConfig& c) -> Ref { return &c.gp.depth_bits; }},
      {"gp.code", "profile", "S", 0, 0, 0,
       "Quality of the GP's per-triangle code: 'assembly' (hand-coded, dual-instruction mode, "
       "scheduled pipelines, fits the instruction cache; over 1 M Phong triangles/s with 32 "
       "GPs) or 'compiled' (C: one instruction per clock, unscheduled, about 100 K/s).",
       [](MachineConfig& c) -> Ref { return &c.gp.code; }, "assembly|compiled"},
      {"gp.fp_latency_clocks", "i860 clocks", "S", 3, 1, 10,
       "Stages of the i860's floating-point adder and single-precision multiplier pipelines: "
       "what an unscheduled operation waits for its result, and what a scheduled chain pays "
       "once to fill and drain.",
       [](MachineConfig& c) -> Ref { return &c.gp.fp_latency_clocks; }},
      {"gp.load_use_clocks", "i860 clocks", "A", 2, 1, 10,
       "Clocks from a load's issue until compiled code can use its value (one delay slot).",
       [](MachineConfig& c) -> Ref { return &c.gp.load_use_clocks; }},
      {"gp.icache_bytes", "bytes", "S", 4096, 256, 1048576, "i860 XR instruction cache.",
       [](MachineConfig& c) -> Ref { return &c.gp.icache_bytes; }},
      {"gp.icache_line_bytes", "bytes", "S", 32, 4, 256, "Instruction-cache line.",
       [](MachineConfig& c) -> Ref { return &c.gp.icache_line_bytes; }},
      {"gp.icache_miss_clocks", "i860 clocks", "A", 6, 0, 1000,
       "Refilling one instruction-cache line from GP memory.",
       [](MachineConfig& c) -> Ref { return &c.gp.icache_miss_clocks; }},
      {"gp.assembly_code_bytes", "bytes", "A", 3584, 256, 1048576,
       "Size of the hand-coded per-triangle loop; the sources say it fits the 4 KB cache.",
       [](MachineConfig& c) -> Ref { return &c.gp.assembly_code_bytes; }},
      {"gp.compiled_code_bytes", "bytes", "A", 12288, 256, 1048576,
       "Size of the compiled per-triangle loop (about 3x the hand-coded one), which does not fit "
       "the instruction cache.",
       [](MachineConfig& c) -> Ref { return &c.gp.compiled_code_bytes; }},
      {"gp.overhead_factor", "ratio", "A", 3.26, 1, 100,
       "Clocks of the counted operations are multiplied by this for the work the count leaves "
       "out (display-list traversal, PPHIGS state, the message-passing OS). Calibrated: the "
       "hand-coded Phong triangle then runs at 1.2 M/s on 32 GPs; the compiled rate, about "
       "100 K/s, follows from the pipeline model (docs/timing.md).",
       [](MachineConfig& c) -> Ref { return &c.gp.overhead_factor; }},
      {"gp.cull_back_faces", "flag", "A", 0, 0, 1,
       "GP library option: 1 drops triangles that face away from the eye (the silhouette "
       "remedy for closed opaque surfaces); 0 draws both sides, lit two-sided.",
       [](MachineConfig& c) -> Ref { return &c.gp.cull_back_faces; }},
      {"ring.channels", "channels", "A", 8, 1, 64,
       "Parallel channels of the ring; 8 x 32 bits x 20 MHz = 5.12 Gb/s matches the paper's "
       "5 Gb/s, but 4 x 40 MHz fits as well.",
       [](MachineConfig& c) -> Ref { return &c.ring.channels; }},
      {"ring.word_bits", "bits", "A", 32, 8, 128, "Width of one channel.",
       [](MachineConfig& c) -> Ref { return &c.ring.word_bits; }},
      {"ring.clock_hz", "Hz", "A", 20e6, 1e6, 1e9, "Ring clock: one word per channel per cycle.",
       [](MachineConfig& c) -> Ref { return &c.ring.clock_hz; }},
      {"ring.hop_latency_cycles", "ring cycles", "A", 1, 0, 1000,
       "Latency of one hop from a ring stop to the next.",
       [](MachineConfig& c) -> Ref { return &c.ring.hop_latency_cycles; }},

      {"renderer.count", "boards", "P", 16, 1, 32,
       "Renderer boards; the paper's machine has up to 16.",
       [](MachineConfig& c) -> Ref { return &c.renderer.count; }},
      {"renderer.clock_hz", "Hz", "P", 40e6, 1e6, 1e9,
       "Array clock: one micro-instruction cycle every 25 ns.",
       [](MachineConfig& c) -> Ref { return &c.renderer.clock_hz; }},
      {"renderer.region_width", "pixels", "P", 128, 64, 1024,
       "Width of the SIMD array and so of a screen region (a multiple of 64).",
       [](MachineConfig& c) -> Ref { return &c.renderer.region_width; }},
      {"renderer.region_height", "pixels", "P", 128, 1, 1024, "Height of the SIMD array.",
       [](MachineConfig& c) -> Ref { return &c.renderer.region_height; }},
      {"renderer.memory_bits", "bits", "P", 208, 16, 1024,
       "Local memory of each pixel processor (ask 'what if' with 256).",
       [](MachineConfig& c) -> Ref { return &c.renderer.memory_bits; }},
      {"renderer.enable_stack_depth", "levels", "A", 8, 1, 64,
       "Saved Enable values per pixel for nested conditionals.",
       [](MachineConfig& c) -> Ref { return &c.renderer.enable_stack_depth; }},
      {"renderer.backing_store_bits", "bits", "P", 4096, 0, 65536,
       "Off-chip backing store per pixel (video RAM).",
       [](MachineConfig& c) -> Ref { return &c.renderer.backing_store_bits; }},
      {"renderer.block_bits", "bits", "S", 32, 1, 64, "Backing-store transfer unit.",
       [](MachineConfig& c) -> Ref { return &c.renderer.block_bits; }},
      {"renderer.backing_store_cycles_per_block", "array cycles", "A", 64, 1, 100000,
       "Time to move one block between pixel memory and backing store; 'much slower than "
       "local memory' is all the sources say.",
       [](MachineConfig& c) -> Ref { return &c.renderer.backing_store_cycles_per_block; }},
      {"renderer.backing_store_overlap", "0 or 1", "P", 1, 0, 1,
       "1: backing-store transfers are asynchronous, as the paper says: a store (bsst) "
       "occupies the backing-store port while the array goes on, a load (bsld) waits only for "
       "the port and its own blocks. 0: every transfer stops the array for its full time.",
       [](MachineConfig& c) -> Ref { return &c.renderer.backing_store_overlap; }},
      {"renderer.overlap_shipping", "0 or 1", "A", 1, 0, 1,
       "1: a finished region's colours are moved to the backing store and cross the ring from "
       "there while the array starts its next region (one region in flight per board). 0: the "
       "Renderer waits until its region has reached the frame buffer.",
       [](MachineConfig& c) -> Ref { return &c.renderer.overlap_shipping; }},
      {"renderer.queue_words", "ring words", "A", 4096, 64, 1048576,
       "Capacity of a Renderer's instruction queue. A GP's bin travels in messages of at "
       "most this size, and a GP stalls until the queue has room for its next message.",
       [](MachineConfig& c) -> Ref { return &c.renderer.queue_words; }},
      {"renderer.balancing", "mode", "A", 0, 0, 0,
       "Assignment of screen regions to Renderers: 'static' (region r to Renderer r mod "
       "count) or 'dynamic' (a Renderer takes the next unrendered region when it finishes "
       "one). The image is identical; only the time differs.",
       [](MachineConfig& c) -> Ref { return &c.renderer.balancing; }, "static|dynamic"},
      {"renderer.packet_overhead_cycles", "array cycles", "A", 8, 0, 100000,
       "Controller cycles to decode one instruction packet and start its procedure.",
       [](MachineConfig& c) -> Ref { return &c.renderer.packet_overhead_cycles; }},

      {"evaluator.coefficient_bits", "bits", "A", 40, 8, 62,
       "Signed width of each coefficient the expression evaluator accepts.",
       [](MachineConfig& c) -> Ref { return &c.evaluator.coefficient_bits; }},
      {"evaluator.result_bits", "bits", "A", 40, 8, 64,
       "Width of the value the evaluator delivers; values wrap modulo 2^n.",
       [](MachineConfig& c) -> Ref { return &c.evaluator.result_bits; }},
      {"evaluator.fraction_bits", "bits", "A", 12, 0, 24,
       "Fraction bits of interpolated attributes (depth, colour, normal); they stream out of "
       "the evaluator first, LSB first, before the integer bits a field loads.",
       [](MachineConfig& c) -> Ref { return &c.evaluator.fraction_bits; }},
      {"evaluator.latency_cycles", "array cycles", "A", 8, 0, 1000,
       "Pipeline latency of the evaluator tree (about log2 of 128 levels plus input stages).",
       [](MachineConfig& c) -> Ref { return &c.evaluator.latency_cycles; }},

      {"evaluator.coefficient_words_per_cycle", "words/cycle", "A", 1, 1, 64,
       "Ring words of a packet's coefficients moved from the instruction queue into the "
       "evaluator's input registers per array cycle.",
       [](MachineConfig& c) -> Ref { return &c.evaluator.coefficient_words_per_cycle; }},
      {"evaluator.double_buffered", "0 or 1", "A", 1, 0, 1,
       "1: the evaluator holds a second set of coefficient registers, so the next packet's "
       "coefficients load while the current packet executes. 0: loading stops the array.",
       [](MachineConfig& c) -> Ref { return &c.evaluator.double_buffered; }},
      {"frame_buffer.bits_per_pixel", "bits", "A", 32, 8, 64,
       "Bits per pixel sent from a Renderer to the frame buffer (24-bit colour in a word).",
       [](MachineConfig& c) -> Ref { return &c.frame_buffer.bits_per_pixel; }},
  };
  return table;
}

const Parameter* find_parameter(const std::string& key) {
  for (const auto& p : parameter_table()) {
    if (key == p.key) return &p;
  }
  return nullptr;
}

std::string format_value(double v, bool is_int) {
  if (is_int) return fmt::format("{}", static_cast<long long>(v));
  return fmt::format("{:g}", v);
}

void assign(MachineConfig& config, const Parameter& p, const nlohmann::json& value,
            const std::string& origin) {
  const Ref ref = p.ref(config);
  if (auto* text = std::get_if<std::string*>(&ref)) {
    const auto allowed = split_choices(p.choices);
    if (value.is_string()) {
      for (const auto& a : allowed) {
        if (a == value.get<std::string>()) {
          **text = a;
          return;
        }
      }
    }
    throw ConfigError(fmt::format("{}: key '{}' must be one of \"{}\" (got {})", origin, p.key,
                                  fmt::join(allowed, "\", \""), value.dump()));
  }
  const bool is_int = std::holds_alternative<int*>(ref);
  if (!value.is_number() || (is_int && !value.is_number_integer())) {
    throw ConfigError(fmt::format("{}: key '{}' must be {} (got {})", origin, p.key,
                                  is_int ? "an integer" : "a number", value.dump()));
  }
  const double v = value.get<double>();
  if (!(v >= p.min && v <= p.max)) {
    throw ConfigError(fmt::format("{}: key '{}' = {} is out of range [{}, {}] {}", origin, p.key,
                                  value.dump(), format_value(p.min, is_int),
                                  format_value(p.max, is_int), p.unit));
  }
  if (is_int) {
    *std::get<int*>(ref) = value.get<int>();
  } else {
    *std::get<double*>(ref) = v;
  }
}

void apply(MachineConfig& config, const nlohmann::json& node, const std::string& prefix,
           const std::string& origin) {
  if (!node.is_object()) {
    throw ConfigError(fmt::format("{}: '{}' must be an object of parameters", origin,
                                  prefix.empty() ? "<top level>" : prefix));
  }
  for (const auto& [name, value] : node.items()) {
    const std::string key = prefix.empty() ? name : prefix + "." + name;
    if (const Parameter* p = find_parameter(key)) {
      assign(config, *p, value, origin);
      continue;
    }
    bool is_section = false;
    for (const auto& p : parameter_table()) {
      if (std::string(p.key).rfind(key + ".", 0) == 0) is_section = true;
    }
    if (!is_section) {
      std::string known;
      const std::string parent = prefix.empty() ? "" : prefix + ".";
      for (const auto& p : parameter_table()) {
        const std::string k = p.key;
        if (k.rfind(parent, 0) != 0) continue;
        const std::string rest = k.substr(parent.size());
        const std::string head = rest.substr(0, rest.find('.'));
        if (known.find("'" + head + "'") == std::string::npos) {
          known += (known.empty() ? "" : ", ") + ("'" + head + "'");
        }
      }
      throw ConfigError(
          fmt::format("{}: unknown key '{}' (expected one of {})", origin, key, known));
    }
    apply(config, value, key, origin);
  }
}

void validate(const MachineConfig& c, const std::string& origin) {
  auto fail = [&](const std::string& what) {
    throw ConfigError(fmt::format("{}: {}", origin, what));
  };
  if (c.renderer.region_width % 64 != 0) {
    fail(
        "key 'renderer.region_width' must be a multiple of 64 (the array is stored 64 pixels "
        "to a host word)");
  }
  if (c.evaluator.result_bits < c.evaluator.coefficient_bits) {
    fail("key 'evaluator.result_bits' must be at least 'evaluator.coefficient_bits'");
  }
  if (c.gp.depth_bits + c.evaluator.fraction_bits + 2 > c.evaluator.coefficient_bits) {
    fail(
        fmt::format("keys 'gp.depth_bits' ({}) + 'evaluator.fraction_bits' ({}) + 2 must not "
                    "exceed 'evaluator.coefficient_bits' ({}): depth would not fit a coefficient",
                    c.gp.depth_bits, c.evaluator.fraction_bits, c.evaluator.coefficient_bits));
  }
  if (c.renderer.backing_store_bits % c.renderer.block_bits != 0) {
    fail("key 'renderer.backing_store_bits' must be a multiple of 'renderer.block_bits'");
  }
}

}  // namespace

MachineConfig MachineConfig::defaults() {
  MachineConfig c;
  for (const auto& p : parameter_table()) {
    const Ref ref = p.ref(c);
    if (auto* i = std::get_if<int*>(&ref)) {
      **i = static_cast<int>(p.default_value);
    } else if (auto* text = std::get_if<std::string*>(&ref)) {
      **text = split_choices(p.choices).front();
    } else {
      *std::get<double*>(ref) = p.default_value;
    }
  }
  return c;
}

MachineConfig MachineConfig::from_json(const nlohmann::json& doc, const std::string& origin) {
  MachineConfig c = defaults();
  apply(c, doc, "", origin);
  validate(c, origin);
  return c;
}

MachineConfig MachineConfig::from_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(fmt::format("{}: cannot open the machine configuration", path));
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw ConfigError(fmt::format("{}: not valid JSON: {}", path, e.what()));
  }
  return from_json(doc, path);
}

void MachineConfig::set(const std::vector<std::string>& assignments) {
  MachineConfig result = *this;
  std::string origin = "--set";
  for (const std::string& assignment : assignments) {
    const auto eq = assignment.find('=');
    origin = fmt::format("--set {}", assignment);
    if (eq == std::string::npos || eq == 0) {
      throw ConfigError(fmt::format("{}: expected KEY=VALUE, e.g. renderer.count=8", origin));
    }
    const std::string key = assignment.substr(0, eq);
    const std::string text = assignment.substr(eq + 1);
    const Parameter* p = find_parameter(key);
    if (!p) {
      throw ConfigError(
          fmt::format("{}: unknown key '{}' (pp5sim config --describe lists them)", origin, key));
    }
    nlohmann::json value;
    try {
      value = p->choices ? nlohmann::json(text) : nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception&) {
      throw ConfigError(
          fmt::format("{}: value '{}' of key '{}' is not a number", origin, text, key));
    }
    assign(result, *p, value, origin);
  }
  validate(result, assignments.size() == 1 ? origin : "--set");
  *this = result;
}

nlohmann::json MachineConfig::to_json() const {
  nlohmann::json doc = nlohmann::json::object();
  MachineConfig copy = *this;
  for (const auto& p : parameter_table()) {
    const std::string key = p.key;
    const auto dot = key.find('.');
    const Ref ref = p.ref(copy);
    auto& slot = doc[key.substr(0, dot)][key.substr(dot + 1)];
    if (auto* i = std::get_if<int*>(&ref)) {
      slot = **i;
    } else if (auto* text = std::get_if<std::string*>(&ref)) {
      slot = **text;
    } else {
      slot = *std::get<double*>(ref);
    }
  }
  return doc;
}

std::vector<ParameterInfo> describe_parameters() {
  std::vector<ParameterInfo> rows;
  MachineConfig scratch;
  for (const auto& p : parameter_table()) {
    const bool is_int = std::holds_alternative<int*>(p.ref(scratch));
    if (p.choices) {
      const auto allowed = split_choices(p.choices);
      rows.push_back({p.key, p.unit, p.confidence, p.description, allowed.front(),
                      fmt::format("{}", fmt::join(allowed, ", "))});
      continue;
    }
    rows.push_back({p.key, p.unit, p.confidence, p.description,
                    format_value(p.default_value, is_int),
                    format_value(p.min, is_int) + " .. " + format_value(p.max, is_int)});
  }
  return rows;
}

}  // namespace pp5
