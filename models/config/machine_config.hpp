#pragma once
// The machine configuration: every assumption pp5sim makes about Pixel-Planes 5, in one
// place, with its unit, its source and its confidence.
//
// Contract: each parameter is declared exactly once, in machine_config.cpp's table, which
// gives its default, range, unit and explanation. Loading a JSON file checks every key
// against that table (unknown keys, wrong types and out-of-range values are errors naming
// the file and the key's path); writing it back gives the fully resolved configuration.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace pp5 {

struct MachineConfig {
  struct Screen {
    int width = 0;
    int height = 0;
  } screen;
  struct Gp {
    int count = 0;
    double clock_hz = 0;
    int subpixel_bits = 0;
    int depth_bits = 0;
    std::string code;  // assembly | compiled
    int fp_latency_clocks = 0;
    int load_use_clocks = 0;
    int icache_bytes = 0;
    int icache_line_bytes = 0;
    int icache_miss_clocks = 0;
    int assembly_code_bytes = 0;
    int compiled_code_bytes = 0;
    double overhead_factor = 0;
    int cull_back_faces = 0;
  } gp;
  struct Ring {
    int channels = 0;
    int word_bits = 0;
    double clock_hz = 0;
    int hop_latency_cycles = 0;
  } ring;
  struct Renderer {
    int count = 0;
    double clock_hz = 0;
    int region_width = 0;
    int region_height = 0;
    int memory_bits = 0;
    int enable_stack_depth = 0;
    int backing_store_bits = 0;
    int block_bits = 0;
    int backing_store_cycles_per_block = 0;
    int packet_overhead_cycles = 0;
    int backing_store_overlap = 0;
    int overlap_shipping = 0;
    int queue_words = 0;
    std::string balancing;  // static | dynamic
  } renderer;
  struct Evaluator {
    int coefficient_bits = 0;
    int result_bits = 0;
    int fraction_bits = 0;
    int latency_cycles = 0;
    int coefficient_words_per_cycle = 0;
    int double_buffered = 0;
  } evaluator;
  struct FrameBuffer {
    int bits_per_pixel = 0;
  } frame_buffer;

  // The defaults: the machine of the 1989 paper, with the assumptions documented.
  static MachineConfig defaults();
  // Defaults overridden by a JSON document; `origin` names it in error messages.
  static MachineConfig from_json(const nlohmann::json& doc, const std::string& origin);
  static MachineConfig from_file(const std::string& path);
  // Applies `key=value` overrides (the command line's --set) all at once: the result is
  // checked after the last one, so linked values can change together; on error the
  // configuration is left unchanged.
  void set(const std::vector<std::string>& assignments);
  void set(const std::string& assignment) { set(std::vector<std::string>{assignment}); }

  nlohmann::json to_json() const;

  int regions_x() const {
    return (screen.width + renderer.region_width - 1) / renderer.region_width;
  }
  int regions_y() const {
    return (screen.height + renderer.region_height - 1) / renderer.region_height;
  }
  int regions() const { return regions_x() * regions_y(); }
};

// One row of the parameter table, for documentation (`pp5sim config --describe`).
struct ParameterInfo {
  std::string key;
  std::string unit;
  std::string confidence;  // P published, S secondary source, A assumption
  std::string description;
  std::string default_value;
  std::string range;
};
std::vector<ParameterInfo> describe_parameters();

// Thrown for every configuration error; the message names the origin and the key.
struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace pp5
