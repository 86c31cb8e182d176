#include "models/config/machine_config.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <variant>

#include "common/read_file.hpp"
#include "common/strict_json.hpp"

namespace pp5 {

namespace {

// A choice-valued key: an enum in MachineConfig, read and written as its index into the
// entry's `choices`.
struct ChoiceRef {
  void* target;
  int (*get)(const void*);
  void (*put)(void*, int);
};
template <class Enum>
ChoiceRef choice(Enum* e) {
  return {e, [](const void* t) { return static_cast<int>(*static_cast<const Enum*>(t)); },
          [](void* t, int v) { *static_cast<Enum*>(t) = static_cast<Enum>(v); }};
}

// A frame parameter: set, or left to its default.
using FrameRef = std::optional<std::int64_t>*;

using Ref = std::variant<int*, double*, ChoiceRef, FrameRef>;

struct Entry {
  std::string key;
  const char* unit;
  const char* confidence;
  double default_value;
  double min;
  double max;
  const char* description;
  Ref (*ref)(MachineConfig&);
  // Choice keys: the allowed values separated by '|', in the enum's order, the first being
  // the default.
  const char* choices = nullptr;
  // Frame parameters: the Parameter index; where a computed one comes from (nullptr: it is
  // settable); whether default and range are given for gp.depth_bits = 24 and scale with
  // 2^(gp.depth_bits - 24).
  int frame = -1;
  const char* computed_from = nullptr;
  bool depth_scaled = false;
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

constexpr int kReferenceDepthBits = 24;

// A settable frame parameter: integer, default and range as declared.
Entry settable(Parameter k, const char* unit, double default_value, double min, double max,
               const char* description, bool depth_scaled = false) {
  Entry e{std::string("frame.") + parameter_name(k),
          unit,
          "A",
          default_value,
          min,
          max,
          description,
          nullptr};
  e.frame = static_cast<int>(k);
  e.depth_scaled = depth_scaled;
  return e;
}

// A frame parameter the GP computes: `from` says from what (shown in the table and in the
// error when someone tries to set it).
Entry computed(Parameter k, const char* unit, const char* description, const char* from) {
  Entry e{std::string("frame.") + parameter_name(k), unit, "A", 0, 0, 0, description, nullptr};
  e.frame = static_cast<int>(k);
  e.computed_from = from;
  return e;
}

// The single declaration of every machine parameter. Confidence: P = the 1989 SIGGRAPH
// paper, S = a secondary source, A = an assumption of this simulator (see
// ../shared/design/pixel-planes-5.md for the sources).
const std::vector<Entry>& parameter_table() {
  static const std::vector<Entry> table = {
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
       [](MachineConfig& c) -> Ref { return choice(&c.gp.code); }, "assembly|compiled"},
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
       [](MachineConfig& c) -> Ref { return choice(&c.renderer.balancing); }, "static|dynamic"},
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

      // The firmware's frame parameters (firmware/isa/interface.hpp names them), sent once per
      // frame; `pp5sim isa` lists them from here. Settable: firmware options of the
      // highlighting and transparency programs. Computed: the GP's, from the scene and the
      // settable ones.
      computed(Parameter::light_x, "x 127",
               "Eye-space unit vector toward the light, x times 127: the scene's first light, "
               "or in the `light` procedure the light it runs for.",
               "the scene's lights (direction)"),
      computed(Parameter::light_y, "x 127", "Light direction y times 127.",
               "the scene's lights (direction)"),
      computed(Parameter::light_z, "x 127", "Light direction z times 127.",
               "the scene's lights (direction)"),
      computed(Parameter::half_x, "x 127",
               "Eye-space half vector (light + view, normalised), x times 127.",
               "the scene's lights and the view direction"),
      computed(Parameter::half_y, "x 127", "Half vector y times 127.",
               "the scene's lights and the view direction"),
      computed(Parameter::half_z, "x 127", "Half vector z times 127.",
               "the scene's lights and the view direction"),
      computed(Parameter::ambient, "1/255", "Ambient reflection, 0..255 (255 = 1.0).",
               "the scene's ambient (scene file \"ambient\", 0 to 1)"),
      computed(Parameter::diffuse, "1/255",
               "Diffuse reflection, 0..255, of the light bound (see the `light` procedure).",
               "the scene's lights (\"diffuse\", 0 to 1)"),
      computed(Parameter::specular, "1/255", "Specular reflection, 0..255, of the light bound.",
               "the scene's lights (\"specular\", 0 to 1)"),
      computed(Parameter::background_red, "1/255", "Background red, 0..255.",
               "the scene's background (scene file \"background\", 0 to 1)"),
      computed(Parameter::background_green, "1/255", "Background green, 0..255.",
               "the scene's background (scene file \"background\", 0 to 1)"),
      computed(Parameter::background_blue, "1/255", "Background blue, 0..255.",
               "the scene's background (scene file \"background\", 0 to 1)"),
      settable(Parameter::highlight_red, "1/255", 255, 0, 255, "Intersection highlight red."),
      settable(Parameter::highlight_green, "1/255", 230, 0, 255, "Highlight green."),
      settable(Parameter::highlight_blue, "1/255", 0, 0, 255, "Highlight blue."),
      settable(Parameter::highlight_opacity, "1/256", 256, 0, 256,
               "Highlight opacity (256 = opaque)."),
      computed(Parameter::highlight_keep, "1/256",
               "256 - highlight_opacity: the weight of the surface colour.",
               "frame.highlight_opacity (derived)"),
      settable(Parameter::threshold, "depth units", 32768, 0, 16777215,
               "The threshold programs flag where |depth - stored depth| < threshold. Default and "
               "range are for gp.depth_bits = 24 and scale with 2^(gp.depth_bits - 24): the "
               "default is 1/512 of the depth range at any depth_bits.",
               true),
      settable(Parameter::delta, "1/16 pixel", 24, 0, 1024,
               "Half-width of fixed-width curves (epsilon programs; also the highlight "
               "report's truth)."),
      computed(Parameter::epsilon_scale, "slope units",
               "(delta/16)^2 * 4^6, so that dz^2 < epsilon_scale * |slope difference|^2 with "
               "slopes in units of 64 depth units per pixel.",
               "frame.delta (derived)"),
      settable(Parameter::silhouette, "x 127", 0, 0, 127,
               "Silhouette remedy: ignore the flag where the frontmost |normal z| * 127 < "
               "silhouette (0: off)."),
      settable(Parameter::surface_opacity, "1/256", 128, 0, 256,
               "Opacity of every surface in the transparency programs."),
      computed(Parameter::surface_keep, "1/256", "256 - surface_opacity.",
               "frame.surface_opacity (derived)"),
      computed(Parameter::normal_epsilon_scale, "slope units",
               "(delta/16)^2 * S^2 / 256, S = depth units per pixel per unit of eye-space slope "
               "at the camera's target distance (epsilon_normal: slopes recovered from "
               "normals).",
               "frame.delta, gp.depth_bits and the scene's camera (derived)"),
      settable(Parameter::layers, "passes", 4, 1, 64,
               "Layers the multipass programs peel (transparent*): their pass count, as they "
               "say `option passes layers`; each pass resends the region's triangles."),
  };
  return table;
}

Ref ref_of(const Entry& e, MachineConfig& c) {
  if (e.frame >= 0) return &c.frame.set[static_cast<std::size_t>(e.frame)];
  return e.ref(c);
}

const Entry* find_parameter(const std::string& key) {
  for (const auto& p : parameter_table()) {
    if (key == p.key) return &p;
  }
  return nullptr;
}

const Entry& frame_entry(Parameter k) {
  static const std::vector<const Entry*> by_index = [] {
    std::vector<const Entry*> v(static_cast<std::size_t>(Parameter::count), nullptr);
    for (const auto& e : parameter_table()) {
      if (e.frame >= 0) v[static_cast<std::size_t>(e.frame)] = &e;
    }
    for (const Entry* e : v) {
      if (!e) throw std::logic_error("a frame parameter is missing from the configuration table");
    }
    return v;
  }();
  return *by_index[static_cast<std::size_t>(k)];
}

std::string format_value(double v, bool is_int) {
  if (is_int) return fmt::format("{}", static_cast<long long>(v));
  return fmt::format("{:g}", v);
}

// A depth-scaled bound: declared for 24 bits, scaled to `depth_bits` (the range's top is one
// below a power of two at every depth).
std::int64_t scale_to_depth(double value, int depth_bits, bool is_max) {
  const double scaled = std::ldexp(is_max ? value + 1 : value, depth_bits - kReferenceDepthBits);
  return std::llround(scaled) - (is_max ? 1 : 0);
}

void assign(MachineConfig& config, const Entry& p, const nlohmann::json& value,
            const std::string& origin) {
  const Ref ref = ref_of(p, config);
  if (auto* c = std::get_if<ChoiceRef>(&ref)) {
    const auto allowed = split_choices(p.choices);
    if (value.is_string()) {
      for (std::size_t i = 0; i < allowed.size(); ++i) {
        if (allowed[i] == value.get<std::string>()) {
          c->put(c->target, static_cast<int>(i));
          return;
        }
      }
    }
    throw ConfigError(fmt::format("{}: key '{}' must be one of \"{}\" (got {})", origin, p.key,
                                  fmt::join(allowed, "\", \""), value.dump()));
  }
  if (p.computed_from) {
    throw ConfigError(fmt::format("{}: key '{}' cannot be set: the GP computes it from {}", origin,
                                  p.key, p.computed_from));
  }
  const bool is_int = !std::holds_alternative<double*>(ref);
  if (!value.is_number() || (is_int && !value.is_number_integer())) {
    throw ConfigError(fmt::format("{}: key '{}' must be {} (got {})", origin, p.key,
                                  is_int ? "an integer" : "a number", value.dump()));
  }
  if (auto* f = std::get_if<FrameRef>(&ref)) {
    // The range of a depth-scaled key depends on gp.depth_bits, which may be set after it:
    // validate() checks every frame value once all keys are in.
    if (value.is_number_unsigned() && value.get<std::uint64_t>() > INT64_MAX) {
      throw ConfigError(
          fmt::format("{}: key '{}' = {} is out of range", origin, p.key, value.dump()));
    }
    **f = value.get<std::int64_t>();
    return;
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
    if (const Entry* p = find_parameter(key)) {
      assign(config, *p, value, origin);
      continue;
    }
    bool is_section = false;
    for (const auto& p : parameter_table()) {
      if (p.key.rfind(key + ".", 0) == 0) is_section = true;
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
  for (int k = 0; k < static_cast<int>(Parameter::count); ++k) {
    if (const auto& v = c.frame.set[static_cast<std::size_t>(k)]) {
      check_frame_parameter(static_cast<Parameter>(k), *v, c.gp.depth_bits, origin);
    }
  }
}

}  // namespace

MachineConfig MachineConfig::defaults() {
  MachineConfig c;
  for (const auto& p : parameter_table()) {
    const Ref ref = ref_of(p, c);
    if (auto* i = std::get_if<int*>(&ref)) {
      **i = static_cast<int>(p.default_value);
    } else if (auto* choice = std::get_if<ChoiceRef>(&ref)) {
      choice->put(choice->target, 0);
    } else if (auto* d = std::get_if<double*>(&ref)) {
      **d = p.default_value;
    } else {
      std::get<FrameRef>(ref)->reset();  // unset: the default, resolved with the frame
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
  nlohmann::json doc;
  try {
    // A configuration is a few kilobytes; 1 MiB is far beyond any.
    doc = parse_strict_json(read_regular_file(path, 1u << 20, "a machine configuration (JSON)"),
                            path);
  } catch (const std::runtime_error& e) {
    throw ConfigError(e.what());
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
    const Entry* p = find_parameter(key);
    if (!p && key.rfind("frame.", 0) == 0) {
      throw ConfigError(
          fmt::format("{}: unknown key '{}': no frame parameter '{}' (pp5sim isa "
                      "lists them)",
                      origin, key, key.substr(6)));
    }
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
    const std::string& key = p.key;
    const auto dot = key.find('.');
    const Ref ref = ref_of(p, copy);
    // Frame parameters: only those the configuration sets. An unset one is not fixed by the
    // configuration: its default follows gp.depth_bits, and a scene file may set it.
    if (auto* f = std::get_if<FrameRef>(&ref)) {
      if (**f) doc[key.substr(0, dot)][key.substr(dot + 1)] = ***f;
      continue;
    }
    auto& slot = doc[key.substr(0, dot)][key.substr(dot + 1)];
    if (auto* i = std::get_if<int*>(&ref)) {
      slot = **i;
    } else if (auto* choice = std::get_if<ChoiceRef>(&ref)) {
      slot = split_choices(p.choices)[static_cast<std::size_t>(choice->get(choice->target))];
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
    if (p.computed_from) {
      rows.push_back({p.key, p.unit, p.confidence, p.description, "computed",
                      fmt::format("from {}", p.computed_from), true});
      continue;
    }
    if (p.choices) {
      const auto allowed = split_choices(p.choices);
      rows.push_back({p.key, p.unit, p.confidence, p.description, allowed.front(),
                      fmt::format("{}", fmt::join(allowed, ", "))});
      continue;
    }
    const bool is_int = !std::holds_alternative<double*>(ref_of(p, scratch));
    std::string range = format_value(p.min, is_int) + " .. " + format_value(p.max, is_int);
    if (p.depth_scaled) range += " (x 2^(gp.depth_bits - 24))";
    rows.push_back(
        {p.key, p.unit, p.confidence, p.description, format_value(p.default_value, is_int), range});
  }
  return rows;
}

std::string name_of(MachineConfig::Gp::Code code) {
  return split_choices(find_parameter("gp.code")->choices)[static_cast<std::size_t>(code)];
}

std::string name_of(MachineConfig::Renderer::Balancing balancing) {
  return split_choices(
      find_parameter("renderer.balancing")->choices)[static_cast<std::size_t>(balancing)];
}

bool frame_parameter_computed(Parameter k) { return frame_entry(k).computed_from != nullptr; }

std::int64_t frame_parameter_default(Parameter k, int depth_bits) {
  const Entry& e = frame_entry(k);
  if (e.computed_from) {
    throw ConfigError(
        fmt::format("key '{}' has no default: the GP computes it from {}", e.key, e.computed_from));
  }
  if (e.depth_scaled) return scale_to_depth(e.default_value, depth_bits, false);
  return static_cast<std::int64_t>(e.default_value);
}

void check_frame_parameter(Parameter k, std::int64_t value, int depth_bits,
                           const std::string& origin) {
  const Entry& e = frame_entry(k);
  if (e.computed_from) {
    throw ConfigError(fmt::format("{}: key '{}' cannot be set: the GP computes it from {}", origin,
                                  e.key, e.computed_from));
  }
  const std::int64_t lo =
      e.depth_scaled ? scale_to_depth(e.min, depth_bits, false) : static_cast<std::int64_t>(e.min);
  const std::int64_t hi =
      e.depth_scaled ? scale_to_depth(e.max, depth_bits, true) : static_cast<std::int64_t>(e.max);
  if (value < lo || value > hi) {
    throw ConfigError(fmt::format(
        "{}: key '{}' = {} is out of range [{}, {}] {}{}", origin, e.key, value, lo, hi, e.unit,
        e.depth_scaled ? fmt::format(" (at gp.depth_bits = {})", depth_bits) : std::string()));
  }
}

std::int64_t resolved_frame_parameter(const MachineConfig& c, Parameter k) {
  const auto& v = c.frame.set[static_cast<std::size_t>(k)];
  return v ? *v : frame_parameter_default(k, c.gp.depth_bits);
}

}  // namespace pp5
