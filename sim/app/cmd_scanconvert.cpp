// pp5sim scanconvert: standard against accurate scan conversion, measured
// (sim/analysis/scan_conversion.hpp).
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <memory>

#include "common/read_file.hpp"
#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "sim/analysis/scan_conversion.hpp"
#include "sim/app/commands.hpp"
#include "sim/output/output_set.hpp"
#include "sim/scene/scene_loader.hpp"

namespace pp5 {

namespace {

namespace fs = std::filesystem;

struct ScanConvertOptions {
  std::vector<std::string> scenes;
  std::string standard = "phong";
  std::string accurate = "accurate";
  std::string config_path;
  std::vector<std::string> sets;
  std::string out_dir = "out/scanconvert";
  bool ablation = false;
  std::vector<int> significand_bits;  // --significand-bits: the precision table
  bool report = false;                // also OUT/report.html
  int threads = default_threads();
};

// A scene's name as a file name: the built-in names are; a path's stem is used otherwise.
std::string file_name(const std::string& scene) {
  const std::string stem = fs::path(scene).stem().string();
  return stem.empty() ? std::string("scene") : stem;
}

int run_scanconvert(const ScanConvertOptions& o) {
  const MachineConfig config = load_config(o.config_path, o.sets);
  // Everything is read and checked before the first frame runs.
  std::vector<std::string> names = o.scenes;
  if (names.empty()) names = builtin_triangle_scene_names();
  std::vector<Scene> scenes;
  for (const std::string& name : names) scenes.push_back(load_scene(name));
  const AssemblerOptions options = assembler_options(config);
  Program standard = assemble_file(resolve_firmware(o.standard), options);
  Program accurate = assemble_file(resolve_firmware(o.accurate), options);
  standard.name = o.standard;
  accurate.name = o.accurate;
  if (!o.significand_bits.empty()) {
    // Every scene at each precision of the GP's arithmetic: one table. Each width is checked
    // (the key's range) before the first frame runs.
    std::vector<MachineConfig> configs;
    for (std::size_t i = 0; i < o.significand_bits.size(); ++i) {
      const int b = o.significand_bits[i];
      for (std::size_t j = 0; j < i; ++j) {
        if (o.significand_bits[j] == b) {
          throw std::runtime_error(fmt::format(
              "--significand-bits: {} is given twice (each width is one set of rows)", b));
        }
      }
      MachineConfig c = config;
      try {
        c.set(std::vector<std::string>{fmt::format("gp.significand_bits={}", b)});
      } catch (const std::exception& e) {
        throw std::runtime_error(fmt::format("--significand-bits {}: {}", b, e.what()));
      }
      configs.push_back(std::move(c));
    }
    prepare_output_folder(o.out_dir, "--out");
    std::vector<ScanConversionAtPrecision> runs;
    for (const MachineConfig& c : configs) {
      ScanConversionAtPrecision run;
      run.significand_bits = c.gp.significand_bits;
      for (const Scene& scene : scenes)
        run.reports.push_back(measure_scan_conversion(c, scene, standard, accurate, o.threads));
      runs.push_back(std::move(run));
    }
    const std::string heading = fmt::format(
        "{} x {} screen, vertices snapped to 1/{} pixel, the GP's coefficients kept "
        "to each number of significant bits (62: exact)",
        config.screen.width, config.screen.height, 1 << config.gp.subpixel_bits);
    const report::Table table = scan_conversion_precision_table(runs);
    report::Report r;
    r.title = "Scan conversion at each precision of the GP's arithmetic";
    r.subtitle = heading;
    r.add_section("precision", "Standard against accurate").blocks.push_back(table);
    OutputSet outputs;
    add_report_outputs(outputs, o.out_dir, r, o.report);
    outputs.commit();
    std::cout << heading << "\n\n"
              << report::markdown(table)
              << fmt::format("\nwrote {}/{}.csv{}\n", o.out_dir, table.id,
                             o.report ? " and report.html" : "");
    return 0;
  }
  if (o.ablation) {
    // Each ingredient of the accurate program alone (scan_conversion.hpp).
    const Program standard_unsnapped = with_depth_expression(
        standard,
        read_regular_file(resolve_firmware(o.standard), kMaxProgramBytes, "a firmware program"),
        "depth", "plane_depth", options);
    const Program accurate_snapped = with_depth_expression(
        accurate,
        read_regular_file(resolve_firmware(o.accurate), kMaxProgramBytes, "a firmware program"),
        "plane_depth", "depth", options);
    std::vector<ScanConversionAblation> rows;
    for (const Scene& scene : scenes) {
      ScanConversionAblation r;
      r.a = measure_scan_conversion(config, scene, standard, accurate_snapped, o.threads);
      r.b = measure_scan_conversion(config, scene, standard_unsnapped, accurate, o.threads);
      rows.push_back(std::move(r));
    }
    const int n = config.gp.significand_bits;
    const std::string heading =
        fmt::format("{} x {} screen, vertices snapped to 1/{} pixel, the GP's coefficients {}",
                    config.screen.width, config.screen.height, 1 << config.gp.subpixel_bits,
                    n < 62 ? fmt::format("kept to {} significant bits", n) : std::string("exact"));
    const report::Table table = scan_conversion_ablation_table(rows);
    std::cout << heading << "\n\n" << report::markdown(table);
    if (o.report) {
      // --report: the table as CSV and the page, into --out.
      report::Report r;
      r.title = "Scan conversion: each ingredient of the accurate program alone";
      r.subtitle = heading;
      r.add_section("ablation", "Ablation").blocks.push_back(table);
      prepare_output_folder(o.out_dir, "--out");
      OutputSet outputs;
      add_report_outputs(outputs, o.out_dir, r, true);
      outputs.commit();
      std::cout << fmt::format("\nwrote {}/scanconvert-ablation.csv and {}/report.html\n",
                               o.out_dir, o.out_dir);
    }
    return 0;
  }
  prepare_output_folder(o.out_dir, "--out");

  std::vector<ScanConversionReport> reports;
  OutputSet outputs;
  std::string notes;
  std::vector<report::Figure> figures;
  for (std::size_t k = 0; k < scenes.size(); ++k) {
    reports.push_back(measure_scan_conversion(config, scenes[k], standard, accurate, o.threads));
    const ScanConversionReport& r = reports.back();
    const std::string base = (fs::path(o.out_dir) / file_name(names[k])).string();
    outputs.add(base + "-standard.png", encode_png(r.standard.image));
    outputs.add(base + "-accurate.png", encode_png(r.accurate.image));
    std::string marked = encode_png(r.marked);
    if (o.report) {
      const std::string file = file_name(names[k]) + "-marked.png";
      figures.push_back({file, r.scene,
                         "The accurate program's image, dimmed, with the pixels that differ from "
                         "the standard one in red and those where the standard one shows a "
                         "hidden surface marked",
                         "image/png", marked, r.scene + ": the pixels that differ", file});
    }
    outputs.add(base + "-marked.png", std::move(marked));
    auto sides = [&r](SideKind k) { return r.sides[static_cast<std::size_t>(k)]; };
    notes += fmt::format(
        "{}: {} triangles, {} edges ({} boundary, {} non-manifold); accurate set-up, triangle "
        "edges (a shared one twice) classified by the neighbour's plane: {}; by their own "
        "unsnapped line: {} boundary, {} "
        "non-manifold, {} degenerate neighbour, {} coplanar; by the snapped edge: {} clipped; "
        "M = {:.0f} depth units/pixel, E = {:.4f} pixel ({:.4f} snap + {:.4f} edge rounding); "
        "standard: {} layer-edge pixels; {} pixels differ\n",
        r.scene, r.triangles, r.edges, r.boundary_edges, r.non_manifold_edges,
        sides(SideKind::plane), sides(SideKind::boundary), sides(SideKind::non_manifold),
        sides(SideKind::degenerate), sides(SideKind::coplanar), sides(SideKind::clipped), r.M, r.E,
        r.E_snap, r.E_edge, r.standard.layer_pixels, r.differing);
  }
  const report::Table tab = scan_conversion_table(reports);
  const std::string table = report::markdown(tab);
  outputs.add((fs::path(o.out_dir) / "scanconvert.md").string(), table + "\n" + notes);
  const int n = config.gp.significand_bits;
  const std::string heading =
      fmt::format("{} x {} screen, vertices snapped to 1/{} pixel, the GP's coefficients {}",
                  config.screen.width, config.screen.height, 1 << config.gp.subpixel_bits,
                  n < 62 ? fmt::format("kept to {} significant bits", n) : std::string("exact"));
  report::Report rep;
  rep.title = "Scan conversion: standard against accurate";
  rep.subtitle = heading;
  report::Section& section = rep.add_section("scanconvert", "Standard against accurate");
  section.blocks.push_back(tab);
  // The per-scene notes, a paragraph each.
  for (std::size_t at = 0, end; at < notes.size(); at = end + 1) {
    end = notes.find('\n', at);
    if (end == std::string::npos) end = notes.size();
    section.blocks.push_back(report::Paragraph{notes.substr(at, end - at)});
  }
  if (!figures.empty()) {
    report::Section& images = rep.add_section("images", "Where the two differ");
    for (report::Figure& f : figures) images.blocks.push_back(std::move(f));
  }
  add_report_outputs(outputs, o.out_dir, rep, o.report);
  // The table and every image together, or none of them (sim/output).
  outputs.commit();
  std::cout << heading << "\n\n"
            << table << "\n"
            << notes
            << fmt::format(
                   "wrote {}/scanconvert.md, scanconvert.csv{} and "
                   "{}/SCENE-{{standard,accurate,marked}}.png\n",
                   o.out_dir, o.report ? ", report.html" : "", o.out_dir);
  return 0;
}

}  // namespace

Command add_scanconvert_command(CLI::App& app) {
  auto o = std::make_shared<ScanConvertOptions>();
  auto* cmd = app.add_subcommand(
      "scanconvert",
      "Standard against accurate scan conversion (Rossignac): on each scene, the depth error "
      "at edge pixels against the exact depth of the true surface at the pixel centre (max, "
      "mean), the pixels where a hidden surface shows through, parity errors across a closed "
      "mesh, and the cost of the fix (array cycles per triangle, bits, GP clocks per "
      "triangle, packet words, frame time). Writes the table and, per scene, both images and "
      "one marking where they differ (red) and where the standard one shows a hidden surface "
      "(yellow).");
  cmd->add_option("-s,--scene", o->scenes,
                  "A scene to measure (repeatable): a built-in name, a mesh file or a scene "
                  "file; default every built-in scene of triangles (not the sphere scenes)");
  cmd->add_option("--standard", o->standard, "The standard program (default phong)");
  cmd->add_option("--accurate", o->accurate, "The accurate program (default accurate)");
  cmd->add_flag("--ablation", o->ablation,
                "Instead of the table and images, the accurate program's two ingredients each "
                "alone: the standard program with depth through the unsnapped vertices, and the "
                "accurate program's classification with the snapped vertices' depth (four rows "
                "per scene; writes nothing)");
  cmd->add_option("--significand-bits", o->significand_bits,
                  "Instead of the table and images, one table of both programs on every scene at "
                  "each of these widths of the GP's arithmetic (gp.significand_bits, 62: exact; "
                  "comma-separated, e.g. 62,24,16,12,10); writes OUT/scanconvert-precision.csv")
      ->delimiter(',')
      ->excludes("--ablation");
  add_config_options(*cmd, o->config_path, o->sets);
  cmd->add_option("-o,--out", o->out_dir, "Output folder (default out/scanconvert)");
  add_report_flag(*cmd, o->report, "OUT");
  cmd->add_option("-j,--threads", o->threads, "Host threads (results are identical for any)")
      ->check(CLI::Range(1, 256));
  return {cmd, [o] { return run_scanconvert(*o); }};
}

}  // namespace pp5
