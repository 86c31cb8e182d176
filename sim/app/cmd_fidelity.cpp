// pp5sim fidelity: what each fidelity level costs and what it loses, measured. Every level
// runs on every chosen scene and program; the table gives host time (the minimum of --runs
// runs), the speed-up over the most detailed level (bit), the frame-time error and whether
// the bottleneck agrees with it, and the pixels and pixel-memory bits that differ from it.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "models/renderer/renderer_board.hpp"
#include "sim/analysis/analytic_validation.hpp"
#include "sim/app/commands.hpp"
#include "sim/output/output_set.hpp"
#include "sim/output/report_html.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/simulation.hpp"

namespace fs = std::filesystem;

namespace pp5 {

namespace {

// Frames of the overlapped run whose sustained period the closed forms are measured against.
constexpr int kSustainedFrames = 4;

struct Level {
  const char* name;
  const char* spec;  // --fidelity
};
// Most detailed first: the reference every other level is measured against.
constexpr Level kLevels[] = {{"bit", "bit"},
                             {"word", "word"},
                             {"timing", "timing"},
                             {"analytic", "analytic"},
                             {"word+analytic", "pixels=word,timing=analytic"}};

struct FidelityOptions {
  std::vector<std::string> scenes;
  std::vector<std::string> firmware{"threshold"};
  std::string config_path;
  std::vector<std::string> sets;
  int runs = 3;
  int threads = default_threads();
  std::string out_dir = "out/fidelity";
  bool report = false;  // also OUT/report.html
  bool analytic_grids = true;
  int heldout = 120;
};

// Every region's whole pixel memory after the region, as the snapshot layout, for counting
// the bits a level leaves different from bit. Each board has its own.
class MemoryKeeper final : public BoardObserver {
 public:
  void begin_packet(const PacketContext&, const ProcedureCode&, const RendererBoard&) override {}
  void after_instruction(int, const Instruction&, ArrayCycles, const RendererBoard&) override {}
  void end_region(int region, const RendererBoard& board) override {
    board.array().read_memory_planes(regions[region]);
  }
  std::map<int, std::vector<std::uint64_t>> regions;
};

// The regions' memories of a whole frame at a pixel level, from a run with an observer on
// every board (not timed: observed boards execute every empty region too).
std::map<int, std::vector<std::uint64_t>> frame_memory(const MachineConfig& config,
                                                       const Scene& scene, const Program& program,
                                                       int threads) {
  std::vector<std::unique_ptr<MemoryKeeper>> keepers;
  for (int k = 0; k < config.renderer.count; ++k)
    keepers.push_back(std::make_unique<MemoryKeeper>());
  simulate_frame(config, scene, program, threads, [&](int k) -> BoardObserver* {
    return keepers[static_cast<std::size_t>(k)].get();
  });
  std::map<int, std::vector<std::uint64_t>> all;
  for (auto& k : keepers) all.insert(k->regions.begin(), k->regions.end());
  return all;
}

std::uint64_t differing_bits(const std::map<int, std::vector<std::uint64_t>>& a,
                             const std::map<int, std::vector<std::uint64_t>>& b) {
  std::uint64_t bits = 0;
  for (const auto& [region, planes] : a) {
    const auto it = b.find(region);
    if (it == b.end() || it->second.size() != planes.size()) {
      throw std::logic_error(
          fmt::format("fidelity: region {} was not executed at both levels", region));
    }
    for (std::size_t i = 0; i < planes.size(); ++i)
      bits += static_cast<std::uint64_t>(__builtin_popcountll(planes[i] ^ it->second[i]));
  }
  return bits;
}

struct Row {
  std::string scene, program, level;
  double host_seconds = 0;
  double speedup = 0;
  double frame_seconds = 0;
  double frame_error = 0;  // relative to bit's frame time
  std::string bottleneck;
  bool bottleneck_agrees = false;
  bool has_pixels = false;
  std::uint64_t pixels_differing = 0;
  bool has_memory = false;
  std::uint64_t bits_differing = 0;
};

int run_fidelity(FidelityOptions o) {
  if (o.scenes.empty()) o.scenes = builtin_scene_names();
  const MachineConfig base = load_config(o.config_path, o.sets);
  if (refuse_below_bit_level(base, "pp5sim fidelity (it measures every level against bit)")) {
    return 2;
  }
  prepare_output_folder(o.out_dir, "--out");
  std::vector<Row> rows;
  // Per scene and program: the sustained frame period of frames overlapped, simulated (the
  // event model's timing, no pixels), against the closed-form estimates of one frame alone
  // (frame.pipelined_frame_seconds at the event and the analytic level).
  struct Sustained {
    std::string scene, program;
    double simulated = 0, event_estimate = 0, analytic_estimate = 0;
  };
  std::vector<Sustained> sustained;
  for (const std::string& scene_name : o.scenes) {
    const Scene scene = load_scene(scene_name);
    for (const std::string& firmware : o.firmware) {
      const Program program = assemble_file(resolve_firmware(firmware), assembler_options(base));
      const std::string program_name = fs::path(program.name).stem().string();
      FrameResult reference;
      Sustained sus{scene.name, program_name};
      {
        MachineConfig timing = base;
        timing.set(fidelity_assignments("timing"));
        const RunSummary run = simulate_frames(timing, std::make_shared<const Scene>(scene),
                                               std::make_shared<const Program>(program), 1,
                                               kSustainedFrames, {}, false);
        sus.simulated = run.sustained_frame_seconds;
        sus.event_estimate = run.estimate_frame_seconds;
      }
      std::map<int, std::vector<std::uint64_t>> reference_memory;
      double reference_host = 0;
      for (const Level& level : kLevels) {
        MachineConfig config = base;
        config.set(fidelity_assignments(level.spec));
        Row row;
        row.scene = scene.name;
        row.program = program_name;
        row.level = level.name;
        FrameResult best;
        for (int run = 0; run < o.runs; ++run) {
          const auto t0 = std::chrono::steady_clock::now();
          FrameResult r = simulate_frame(config, scene, program, o.threads);
          const double host =
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          if (run == 0 || host < row.host_seconds) row.host_seconds = host;
          if (run == 0) best = std::move(r);
        }
        if (std::string(level.name) == "analytic")
          sus.analytic_estimate = best.stats.real("frame.pipelined_frame_seconds");
        if (std::string(level.name) == "bit") {
          reference = best;
          reference_host = row.host_seconds;
        }
        row.frame_seconds = best.frame_seconds;
        row.speedup = reference_host / row.host_seconds;
        row.frame_error = (best.frame_seconds - reference.frame_seconds) / reference.frame_seconds;
        row.bottleneck = best.stats.text("timing.bottleneck");
        row.bottleneck_agrees = row.bottleneck == reference.stats.text("timing.bottleneck");
        row.has_pixels = config.fidelity.pixels != MachineConfig::Fidelity::Pixels::none;
        if (row.has_pixels) {
          const std::vector<std::uint8_t>& a = best.image.flat().rgb;
          const std::vector<std::uint8_t>& b = reference.image.flat().rgb;
          for (std::size_t p = 0; p + 2 < a.size(); p += 3) {
            if (!std::equal(a.begin() + p, a.begin() + p + 3, b.begin() + p)) {
              ++row.pixels_differing;
            }
          }
        }
        // Memory is compared region by region, which needs the event model's regions (an
        // observer); the analytic model runs the same regions, on boards in another order.
        if (row.has_pixels && config.fidelity.timing == MachineConfig::Fidelity::Timing::event) {
          auto memory = frame_memory(config, scene, program, o.threads);
          if (std::string(level.name) == "bit") reference_memory = std::move(memory);
          row.has_memory = true;
          row.bits_differing =
              std::string(level.name) == "bit" ? 0 : differing_bits(reference_memory, memory);
        }
        std::cerr << fmt::format("{} / {} / {}: {:.3f} s\n", row.scene, row.program, row.level,
                                 row.host_seconds);
        rows.push_back(row);
      }
      sustained.push_back(sus);
    }
  }

  auto pct = [](double e) { return fmt::format("{:+.2f}%", 100 * e); };
  report::Table table;
  table.id = "fidelity";
  {
    using namespace report;
    auto keyed = [](Column c, const std::string& heading, const std::string& key) {
      c.heading = heading;
      c.key = key;
      return c;
    };
    table.columns = {
        keyed(text_column("scene"), "scene", "scene"),
        keyed(text_column("program"), "program", "program"),
        keyed(text_column("level", "The fidelity level"), "level", "level"),
        keyed(real_column("host s", "s", 4, "Host seconds of the run, the fastest of --runs"),
              fmt::format("host s (min of {})", o.runs), "host_seconds"),
        keyed(real_column("speed-up", "", 1, "The bit level's host time / this level's"),
              "speed-up", "speedup"),
        keyed(real_column("frame ms", "ms", 3, "Simulated frame time"), "frame ms", "frame_ms"),
        keyed(real_column("frame-time error", "%", 2, "Against the bit level's frame time"),
              "frame-time error", "frame_time_error_percent"),
        keyed(text_column("bottleneck"), "bottleneck", "bottleneck"),
        keyed(text_column("agrees", "Whether the bottleneck is the bit level's"), "agrees",
              "bottleneck_agrees"),
        keyed(headed(integer_column("pixels differing", "pixels", "Pixels that differ from bit's"),
                     "pixels differing", Align::right),
              "pixels differing", "pixels_differing"),
        keyed(headed(integer_column("memory bits differing", "bits",
                                    "Pixel-memory bits (every region's whole memory, compared "
                                    "after the region) that differ from bit's"),
                     "memory bits differing", Align::right),
              "memory bits differing", "memory_bits_differing"),
    };
  }
  for (const Row& r : rows) {
    using report::Cell;
    const Cell pixels =
        r.has_pixels ? Cell(r.pixels_differing) : Cell::shown_as(Cell::missing(), "no image");
    const Cell bits = r.has_memory   ? Cell(r.bits_differing)
                      : r.has_pixels ? Cell::shown_as(Cell::missing(), "not compared")
                                     : Cell::shown_as(Cell::missing(), "no memory");
    table.add_row({r.scene, r.program, r.level, r.host_seconds, r.speedup, r.frame_seconds * 1e3,
                   Cell::shown_as(100 * r.frame_error, pct(r.frame_error)), r.bottleneck,
                   r.bottleneck_agrees ? "yes" : "no", pixels, bits});
  }
  std::string md = report::markdown(table);
  report::Report page;
  page.title = "Fidelity levels against the bit level";
  page.add_section("fidelity", "Levels").blocks.push_back(table);
  // The closed forms against the simulated sustained period.
  report::Table sustained_table;
  sustained_table.id = "sustained";
  {
    using namespace report;
    sustained_table.columns = {
        text_column("scene"),
        text_column("program"),
        headed(real_column("sustained ms", "ms", 3,
                           "Simulated sustained frame period of frames overlapped"),
               fmt::format("sustained ms (simulated, {} frames overlapped)", kSustainedFrames),
               Align::right),
        headed(real_column("estimate ms (event)", "ms", 3,
                           "Closed-form estimate from one frame alone at the event level"),
               "estimate ms (event, one frame)", Align::right),
        headed(real_column("event error", "%", 2, "Event-level estimate against the simulated"),
               "error", Align::right),
        headed(real_column("estimate ms (analytic)", "ms", 3,
                           "Closed-form estimate at the analytic level"),
               "estimate ms (analytic)", Align::right),
        headed(
            real_column("analytic error", "%", 2, "Analytic-level estimate against the simulated"),
            "error", Align::right),
    };
  }
  for (const Sustained& t : sustained) {
    using report::Cell;
    auto error = [&t](double e) { return t.simulated > 0 ? e / t.simulated - 1 : 0.0; };
    sustained_table.add_row(
        {t.scene, t.program, t.simulated * 1e3, t.event_estimate * 1e3,
         Cell::shown_as(100 * error(t.event_estimate), pct(error(t.event_estimate))),
         t.analytic_estimate * 1e3,
         Cell::shown_as(100 * error(t.analytic_estimate), pct(error(t.analytic_estimate)))});
  }
  const std::string sustained_md = report::markdown(sustained_table);
  const std::string sustained_heading =
      "The sustained frame period of frames overlapped (simulated: a GP sets up frame n + 1 "
      "while the Renderers draw frame n) against the closed-form estimate "
      "frame.pipelined_frame_seconds of one frame alone, at the event and the analytic "
      "level:";
  md += "\n" + sustained_heading + "\n\n" + sustained_md;
  {
    report::Section& section = page.add_section("sustained", "Frames in sequence");
    section.blocks.push_back(report::Paragraph{sustained_heading});
    section.blocks.push_back(sustained_table);
  }
  if (o.analytic_grids) {
    // The analytic level against the event level on machines it was not adjusted on: the
    // held-out grid (seeded, drawn before either model was looked at) beside the tuning one.
    const ProgramLoader load = [](const std::string& name, const MachineConfig& c) {
      return assemble_file(resolve_firmware(name), assembler_options(c));
    };
    std::vector<AnalyticValidation> grids = {
        validate_analytic("tuning", analytic_tuning_grid(), load),
        validate_analytic("tuning (dynamic)", analytic_tuning_grid("dynamic"), load)};
    for (const std::uint64_t seed : kLookedAtSeeds) {
      grids.push_back(validate_analytic(fmt::format("looked at (seed {:#x})", seed),
                                        analytic_heldout_grid(o.heldout, seed), load));
    }
    for (const std::uint64_t seed : kHeldOutSeeds) {
      grids.push_back(validate_analytic(fmt::format("held-out (seed {:#x})", seed),
                                        analytic_heldout_grid(o.heldout, seed), load));
    }
    const std::string heading =
        "The analytic level against the event level (frame time, no pixels), on the grids "
        "it was adjusted on (the tuning grids, and seeded grids that were held out until they "
        "were looked at) and on held-out grids of seeded machines (scenes, programs, screens, "
        "GPs, Renderers, channels, queue words, balancing, shipping, hop latency, double "
        "buffering, code profile):";
    const report::Table grid_table = analytic_validation_table(grids);
    md += "\n" + heading + "\n\n" + report::markdown(grid_table);
    report::Section& section = page.add_section("analytic", "The analytic level's validation");
    section.blocks.push_back(report::Paragraph{heading});
    section.blocks.push_back(grid_table);
    report::Table points;
    points.id = "analytic_validation";
    points.columns = {report::text_column("grid"),
                      report::text_column("machine"),
                      report::real_column("event_seconds", "", -1),
                      report::real_column("analytic_seconds", "", -1),
                      report::real_column("error", "", -1),
                      report::real_column("closed_form_seconds", "", -1),
                      report::text_column("event_bottleneck"),
                      report::text_column("analytic_bottleneck")};
    for (const AnalyticValidation& v : grids) {
      for (const AnalyticPoint& p : v.points) {
        points.add_row({v.grid, p.machine.label(), p.event_seconds, p.analytic_seconds, p.error(),
                        p.closed_form_seconds, p.event_bottleneck, p.analytic_bottleneck});
      }
    }
    points.title = "Every machine (analytic_validation.csv)";
    section.blocks.push_back(std::move(points));
  }
  const fs::path dir(o.out_dir);
  OutputSet outputs;
  outputs.add((dir / "fidelity.md").string(), md);
  outputs.add((dir / "sustained.md").string(), sustained_md);
  // fidelity.csv, sustained.csv, with the grids analytic-grids.csv and analytic_validation.csv,
  // with --report the page.
  add_report_outputs(outputs, o.out_dir, page, o.report);
  outputs.commit();
  std::cout << md;
  std::cout << fmt::format(
      "\nwrote {0}/fidelity.md, {0}/fidelity.csv, {0}/sustained.csv{1}{2}\n", o.out_dir,
      o.analytic_grids
          ? fmt::format(", {0}/analytic-grids.csv, {0}/analytic_validation.csv", o.out_dir)
          : "",
      o.report ? ", " + o.out_dir + "/report.html" : "");
  return 0;
}

}  // namespace

Command add_fidelity_command(CLI::App& app) {
  auto o = std::make_shared<FidelityOptions>();
  auto* cmd = app.add_subcommand(
      "fidelity",
      "Run every fidelity level (bit, word, timing, analytic, word+analytic) on scenes and "
      "programs and tabulate what each costs in host time and loses against bit");
  cmd->add_option("-s,--scene", o->scenes,
                  "A scene (repeatable): built-in name, mesh or scene file [every built-in scene]");
  cmd->add_option("-f,--firmware", o->firmware,
                  "A program (repeatable), resolved as render's --firmware does")
      ->capture_default_str();
  add_config_options(*cmd, o->config_path, o->sets);
  cmd->add_option("--runs", o->runs, "Runs of each level; the table gives the fastest")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("-j,--threads", o->threads, "Host threads for the pixel arrays")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  cmd->add_option("-o,--out", o->out_dir, "Output folder for fidelity.md and fidelity.csv")
      ->capture_default_str();
  add_report_flag(*cmd, o->report, "OUT");
  cmd->add_flag("!--no-analytic-grids", o->analytic_grids,
                "Skip the analytic level's validation on the tuning and held-out grids");
  cmd->add_option("--heldout", o->heldout,
                  "Machines of each seeded grid (the held-out grids and those looked at)")
      ->check(CLI::Range(2, 100000))
      ->capture_default_str();
  return {cmd, [o] { return run_fidelity(*o); }};
}

}  // namespace pp5
