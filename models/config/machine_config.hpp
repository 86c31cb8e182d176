#pragma once
// The machine configuration: every assumption pp5sim makes about Pixel-Planes 5, in one
// place, with its unit, its source and its confidence.
//
// Contract: each parameter is declared exactly once, in machine_config.cpp's table, which
// gives its default, range, unit and explanation. Loading a JSON file checks every key
// against that table (unknown keys, wrong types, out-of-range values, a choice not among its
// values and duplicate keys are errors naming the file and the key's path); writing it back
// gives the fully resolved configuration, choices by name.
//
// The table's `frame.` section declares the firmware's frame parameters (firmware/isa/
// interface.hpp names them, `Parameter`): the settable ones (frame.threshold, ...) with
// default and range, and the computed ones (from the scene's lights, ambient and background,
// or derived from other parameters) with where they come from; setting a computed one is an
// error that says why. A settable frame parameter left unset takes its default when the
// frame is built (resolved_frame_parameter), so defaults that follow other keys (threshold
// follows gp.depth_bits) stay consistent under --set.
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "firmware/isa/interface.hpp"

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
    int significand_bits = 0;  // the GP's arithmetic (gp.significand_bits)
    int depth_bits = 0;
    enum class Code { assembly, compiled };
    Code code = Code::assembly;
    int fp_latency_clocks = 0;
    int load_use_clocks = 0;
    int icache_bytes = 0;
    int icache_line_bytes = 0;
    int icache_miss_clocks = 0;
    int assembly_code_bytes = 0;
    int compiled_code_bytes = 0;
    double overhead_factor = 0;
    // How the overhead factor applies to the counted clocks (I860Params::overhead_form).
    enum class OverheadForm { multiply, add };
    OverheadForm overhead_form = OverheadForm::multiply;
    int cull_back_faces = 0;
    // What a GP does for the second and later passes of a multipass program: send the binned
    // packets it kept again, or traverse and transform its share of the display list again.
    enum class Multipass { resend, retraverse };
    Multipass multipass = Multipass::resend;
    // Which of several GPs waiting to send takes a Renderer's queue room first
    // (RegionScheduler): the nearest it on the ring, the lowest-numbered, or each in turn.
    enum class SendOrder { nearest, lowest, round_robin };
    SendOrder send_order = SendOrder::nearest;
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
    enum class Balancing { static_, dynamic };  // "static" is a keyword
    Balancing balancing = Balancing::static_;
    // The multiply's microcode (mul): every pass adds over the destination from its bit up
    // (full), or only over the partial product's window (window).
    enum class MultiplyMicrocode { full, window };
    MultiplyMicrocode multiply_microcode = MultiplyMicrocode::full;
  } renderer;
  struct Evaluator {
    int coefficient_bits = 0;
    int result_bits = 0;
    int fraction_bits = 0;
    int latency_cycles = 0;
    int coefficient_words_per_cycle = 0;
    int double_buffered = 0;
    // The order the evaluator delivers a value's bits in (timing only: the values are the
    // same).
    enum class BitOrder { lsb_first, msb_first };
    BitOrder bit_order = BitOrder::lsb_first;
  } evaluator;
  struct FrameBuffer {
    int bits_per_pixel = 0;
  } frame_buffer;
  // A run of frames (Session::run_frames): how the GPs overlap the Renderers.
  struct Frames {
    int gp_bins = 2;
    enum class GpStart { overlap, after_frame };
    GpStart gp_start = GpStart::overlap;
    // When a GP sends a region's packets: once its whole share is set up (after_geometry), or
    // a message as soon as it is full while the set-up goes on (when_full).
    enum class GpSend { after_geometry, when_full };
    GpSend gp_send = GpSend::after_geometry;
  } frames;
  // How much of the machine a run simulates (README "Fidelity levels"): what executes the
  // pixels (bit-serial, a whole field at a time, or nothing), whether time comes from the
  // event model or a closed form, and the window of regions whose pixels execute (columns and
  // rows of regions from window_x, window_y; 0 columns or rows: to the screen's edge).
  struct Fidelity {
    enum class Pixels { bit, word, none };
    Pixels pixels = Pixels::bit;
    enum class Timing { event, analytic };
    Timing timing = Timing::event;
    int window_x = 0;
    int window_y = 0;
    int window_columns = 0;
    int window_rows = 0;
    // Whether region (column, row) executes its pixels.
    bool executes(int column, int row) const {
      return pixels != Pixels::none && column >= window_x && row >= window_y &&
             (window_columns == 0 || column < window_x + window_columns) &&
             (window_rows == 0 || row < window_y + window_rows);
    }
  } fidelity;
  // Frame parameters set by the configuration (file, --set frame.NAME, --param NAME); unset
  // ones take their declared default. Indexed by Parameter; computed ones are never set.
  struct Frame {
    std::array<std::optional<std::int64_t>, static_cast<int>(Parameter::count)> set;
  } frame;

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
  // Region r's first pixel column and row (regions are numbered row-major).
  int region_x0(int r) const { return (r % regions_x()) * renderer.region_width; }
  int region_y0(int r) const { return (r / regions_x()) * renderer.region_height; }
};

// The names of the choice values, as the configuration and stats.json spell them.
std::string name_of(MachineConfig::Gp::Code code);
std::string name_of(MachineConfig::Renderer::Balancing balancing);
std::string name_of(MachineConfig::Renderer::MultiplyMicrocode microcode);
std::string name_of(MachineConfig::Evaluator::BitOrder order);
std::string name_of(MachineConfig::Gp::Multipass multipass);
std::string name_of(MachineConfig::Gp::OverheadForm form);
std::string name_of(MachineConfig::Gp::SendOrder order);

// How a timing constant's value was obtained (docs/timing.md, "Calibration"):
//  - fitted: chosen so that the simulator reproduces a published figure, which the entry
//    names with its source; reproducing that figure is then a consistency check, not a test
//    of the model;
//  - derived: follows from a published or data-sheet figure (named), or from other entries;
//  - assumed: no source gives it; the entry gives a plausible range.
// `none`: not a timing constant (sizes of the workload, firmware options, capacities).
enum class Calibration { none, fitted, derived, assumed };
const char* calibration_name(Calibration c);  // "fitted", "derived", "assumed" or "-"
std::string name_of(MachineConfig::Fidelity::Pixels pixels);
std::string name_of(MachineConfig::Fidelity::Timing timing);

// One row of the parameter table, for documentation (`pp5sim config --describe`).
struct ParameterInfo {
  std::string key;
  std::string unit;
  std::string confidence;  // P published, S secondary source, A assumption
  std::string description;
  std::string default_value;  // for a computed frame parameter: "computed"
  std::string range;          // for a computed frame parameter: where it comes from
  bool computed = false;
  Calibration calibration = Calibration::none;
  std::string basis;  // fitted: to which figure (source); derived: from what; assumed: why
  // The ends of the plausible range of a fitted or assumed constant, each as the --set
  // assignments (KEY=VALUE) that put the machine there; linked keys move together (a ring of
  // 4 channels runs at 40 MHz to keep the published 5 Gb/s). Empty otherwise.
  std::vector<std::string> low;
  std::vector<std::string> high;
  // A fitted constant: the ids of the published figures its fit consumed (PublishedFigure).
  std::vector<std::string> consumes;
};
std::vector<ParameterInfo> describe_parameters();

// The fitted constants whose fit consumed published figure `id` (ParameterInfo::consumes):
// reproducing that figure is a consistency check, not evidence.
std::vector<std::string> fits_consuming(const std::string& id);

// Frame parameters (the `frame.` section). Contract:
//  - frame_parameter_default(k, depth_bits): the declared default of settable parameter k
//    (threshold scales with 2^depth_bits: 32768 at the default 24 bits); throws ConfigError
//    for a computed one.
//  - check_frame_parameter(k, value, depth_bits, origin): throws ConfigError naming origin and
//    the key (frame.NAME) if k is computed (saying from what) or value is outside its range.
//  - resolved_frame_parameter(c, k): c.frame.set[k], else the default for c.gp.depth_bits.
bool frame_parameter_computed(Parameter k);
std::int64_t frame_parameter_default(Parameter k, int depth_bits);
void check_frame_parameter(Parameter k, std::int64_t value, int depth_bits,
                           const std::string& origin);
std::int64_t resolved_frame_parameter(const MachineConfig& c, Parameter k);

// Thrown for every configuration error; the message names the origin and the key.
struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace pp5
