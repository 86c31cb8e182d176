// pp5sim csg: the parity and depth-interval applications of issue 15 against a CPU ray
// caster (sim/analysis/csg.hpp): point in solid by parity, standard and accurate;
// interference; CSG rendering; and transparency, front to back and back to front, against
// every layer composited in double (sim/analysis/transparency.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "sim/analysis/csg.hpp"
#include "sim/analysis/transparency.hpp"
#include "sim/app/commands.hpp"
#include "sim/output/output_set.hpp"
#include "sim/scene/scene_loader.hpp"

namespace pp5 {

namespace {

namespace fs = std::filesystem;

struct CsgOptions {
  std::vector<std::string> scenes;
  std::vector<std::string> programs = {"parity", "parity_accurate"};
  std::vector<std::string> epsilon_programs = {"parity", "parity_epsilon", "parity_behind"};
  std::vector<std::string> assemblies;
  std::vector<std::string> interference = {"interference", "interference_accurate"};
  std::vector<std::string> csg_scenes;
  std::vector<std::string> csg_programs = {"csg", "csg_accurate", "csg_layers"};
  std::string pruning_program = "csg";
  std::vector<std::string> transparency_scenes;
  std::vector<std::string> transparency_programs = {"transparent", "transparent_interval"};
  std::vector<int> layers = {2, 4, 8};
  double opacity = 0.5;
  std::vector<std::string> section_scenes;
  std::vector<std::string> section_programs = {"section", "section_accurate"};
  std::string application = "all";
  std::string config_path;
  std::vector<std::string> sets;
  std::string out_dir = "out/csg";
  bool report = false;  // also OUT/report.html
  int threads = default_threads();
};

int run_csg(const CsgOptions& o) {
  const MachineConfig config = load_config(o.config_path, o.sets);
  std::vector<std::string> names = o.scenes;
  if (names.empty()) names = parity_scene_names();
  std::vector<Scene> scenes;
  for (const std::string& name : names) scenes.push_back(make_parity_scene(name));
  std::vector<Program> programs;
  for (const std::string& name : o.programs) {
    programs.push_back(assemble_file(resolve_firmware(name), assembler_options(config)));
    programs.back().name = name;
  }
  const bool parity = o.application == "parity" || o.application == "all";
  const bool regularised = o.application == "epsilon" || o.application == "all";
  std::vector<Scene> epsilon_scenes;
  for (const std::string& name : regularised ? epsilon_scene_names() : std::vector<std::string>{}) {
    epsilon_scenes.push_back(make_parity_scene(name));
  }
  std::vector<Program> epsilon_programs;
  for (const std::string& name : regularised ? o.epsilon_programs : std::vector<std::string>{}) {
    epsilon_programs.push_back(assemble_file(resolve_firmware(name), assembler_options(config)));
    epsilon_programs.back().name = name;
  }
  const bool assembly = o.application == "interference" || o.application == "all";
  const bool rendering = o.application == "csg" || o.application == "all";
  const bool transparency = o.application == "transparency" || o.application == "all";
  // Transparency: a scene whose every surface is opaque (a built-in one) gets --opacity.
  std::vector<Scene> see_through;
  for (const std::string& name : transparency ? o.transparency_scenes.empty()
                                                    ? std::vector<std::string>{"torus"}
                                                    : o.transparency_scenes
                                              : std::vector<std::string>{}) {
    see_through.push_back(load_scene(name));
    Mesh& mesh = see_through.back().mesh;
    if (std::all_of(mesh.vertices.begin(), mesh.vertices.end(),
                    [](const Vertex& v) { return v.opacity >= 1.0f; })) {
      for (Vertex& v : mesh.vertices) v.opacity = static_cast<float>(o.opacity);
    }
  }
  const bool sections = o.application == "section" || o.application == "all";
  std::vector<Scene> cut;
  for (const std::string& name :
       sections ? o.section_scenes.empty() ? section_scene_names() : o.section_scenes
                : std::vector<std::string>{}) {
    cut.push_back(make_parity_scene(name));
  }
  std::vector<Program> section_programs;
  for (const std::string& name : sections ? o.section_programs : std::vector<std::string>{}) {
    section_programs.push_back(assemble_file(resolve_firmware(name), assembler_options(config)));
    section_programs.back().name = name;
  }
  std::vector<Program> see_through_programs;
  for (const std::string& name :
       transparency ? o.transparency_programs : std::vector<std::string>{}) {
    see_through_programs.push_back(
        assemble_file(resolve_firmware(name), assembler_options(config)));
    see_through_programs.back().name = name;
  }
  std::vector<Scene> csg_scenes;
  if (rendering) {
    std::vector<std::string> names = csg_scene_names();
    for (const std::string& name : csg_quadric_scene_names()) names.push_back(name);
    for (const std::string& name : o.csg_scenes.empty() ? names : o.csg_scenes)
      csg_scenes.push_back(make_parity_scene(name));
  }
  std::vector<Program> csg_programs;
  for (const std::string& name : rendering ? o.csg_programs : std::vector<std::string>{}) {
    csg_programs.push_back(assemble_file(resolve_firmware(name), assembler_options(config)));
    csg_programs.back().name = name;
  }
  std::vector<Scene> pruning_scenes;
  std::vector<Program> pruning_programs;
  if (rendering) {
    for (const std::string& name : csg_pruning_scene_names())
      pruning_scenes.push_back(make_parity_scene(name));
    pruning_programs.push_back(
        assemble_file(resolve_firmware(o.pruning_program), assembler_options(config)));
    pruning_programs.back().name = o.pruning_program;
  }
  std::vector<std::string> assembly_names = o.assemblies;
  if (assembly_names.empty()) assembly_names = interference_scene_names();
  std::vector<Scene> assemblies;
  if (assembly) {
    for (const std::string& name : assembly_names) assemblies.push_back(make_parity_scene(name));
  }
  std::vector<Program> interference;
  for (const std::string& name : o.interference) {
    interference.push_back(assemble_file(resolve_firmware(name), assembler_options(config)));
    interference.back().name = name;
  }
  std::vector<ParityMeasure> rows;
  std::vector<ParityMeasure> epsilon_rows;
  std::vector<InterferenceMeasure> interfering;
  std::vector<CsgMeasure> rendered;
  std::vector<CsgPruning> pruning;
  std::vector<TransparencyMeasure> composited;
  std::vector<SectionMeasure> capped;
  // Every input is read: only now the output folder (a bad scene or program leaves none).
  prepare_output_folder(o.out_dir, "--out");
  OutputSet outputs;
  std::vector<report::Figure> figures;  // --report: each frame the machine drew
  auto images = [&](const std::string& scene, const std::string& program, const RgbImage& image,
                    const RgbImage& difference) {
    const std::string stem = fmt::format("{}-{}", scene, program);
    const std::string base = (fs::path(o.out_dir) / stem).string();
    std::string png = encode_png(image);
    if (o.report) {
      figures.push_back({stem, fmt::format("{}, {}", scene, program),
                         fmt::format("The machine's frame ({0}-difference.png: white where it "
                                     "disagrees with the reference, grey where not compared)",
                                     stem),
                         "image/png", png, fmt::format("{} drawn by {}", scene, program),
                         stem + ".png"});
    }
    outputs.add(base + ".png", std::move(png));
    outputs.add(base + "-difference.png", encode_png(difference));
  };
  for (const Scene& scene : parity ? scenes : std::vector<Scene>{}) {
    for (const Program& program : programs) {
      rows.push_back(measure_parity(config, scene, program, o.threads));
      images(scene.name, program.name, rows.back().image, rows.back().difference);
    }
  }
  for (const Scene& scene : epsilon_scenes) {
    for (const Program& program : epsilon_programs) {
      epsilon_rows.push_back(measure_parity(config, scene, program, o.threads));
      images("epsilon-" + scene.name, program.name, epsilon_rows.back().image,
             epsilon_rows.back().difference);
    }
  }
  for (const Scene& scene : assemblies) {
    for (const Program& program : interference) {
      interfering.push_back(measure_interference(config, scene, program, o.threads));
      images(scene.name, program.name, interfering.back().image, interfering.back().difference);
    }
  }
  for (const Scene& scene : csg_scenes) {
    for (const Program& program : csg_programs) {
      // A program without sphere procedures draws no quadric solid: among the default scenes
      // left out; a scene named on the command line gets the pass plan's error.
      if (o.csg_scenes.empty() && !program.procedure(Procedure::sphere_surface).defined &&
          std::any_of(scene.solids.begin(), scene.solids.end(),
                      [](const Solid& s) { return s.last_sphere > s.first_sphere; })) {
        continue;
      }
      rendered.push_back(measure_csg(config, scene, program, o.threads));
      images(scene.name, program.name, rendered.back().image, rendered.back().difference);
    }
  }
  for (const Scene& scene : pruning_scenes) {
    for (const Program& program : pruning_programs) {
      pruning.push_back(measure_csg_pruning(config, scene, program, o.threads));
    }
  }
  for (const Scene& scene : see_through) {
    for (int layers : o.layers) {
      MachineConfig c = config;
      c.set({fmt::format("frame.layers={}", layers)});
      for (const Program& program : see_through_programs) {
        composited.push_back(measure_transparency(c, scene, program, o.threads));
        images(fmt::format("{}-layers{}", scene.name, layers), program.name,
               composited.back().image, composited.back().difference);
      }
    }
  }
  for (const Scene& scene : cut) {
    for (const Program& program : section_programs) {
      capped.push_back(measure_section(config, scene, program, o.threads));
      images(scene.name, program.name, capped.back().surface.image,
             capped.back().surface.difference);
    }
  }
  const std::string heading = fmt::format(
      "{} x {} screen; pixels compared with a double-precision reference at "
      "the pixel centre (a ray caster; for transparency every layer composited), "
      "those within 0.75 pixel of a change left out",
      config.screen.width, config.screen.height);
  report::Report r;
  r.title = "Rossignac's applications on the machine";
  r.subtitle = heading;
  std::string tables;
  auto add = [&](const std::string& id, const std::string& title, report::Table table) {
    tables += report::markdown(table) + "\n";
    r.add_section(id, title).blocks.push_back(std::move(table));
  };
  if (parity) add("parity", "Point in solid (parity)", parity_table(rows));
  if (regularised) add("epsilon", "Epsilon regularisation", epsilon_table(epsilon_rows));
  if (assembly) add("interference", "Interference", interference_table(interfering));
  if (rendering) {
    add("csg", "CSG rendering", csg_render_table(rendered));
    add("pruning", "Goldfeather's pruning", csg_pruning_table(pruning));
  }
  if (transparency) add("transparency", "Transparency", transparency_table(composited));
  if (sections) add("section", "Cross-sections", section_table(capped));
  if (!figures.empty()) {
    report::Section& frames = r.add_section("frames", "Frames");
    for (report::Figure& f : figures) frames.blocks.push_back(std::move(f));
  }
  outputs.add((fs::path(o.out_dir) / "csg.md").string(), tables);
  add_report_outputs(outputs, o.out_dir, r, o.report);
  outputs.commit();
  std::cout << heading << "\n\n"
            << tables
            << fmt::format(
                   "wrote {0}/csg.md, a CSV of each table ({0}/csg-*.csv){1} and "
                   "{0}/SCENE-PROGRAM{{,-difference}}.png (the epsilon table's as "
                   "epsilon-SCENE-PROGRAM)\n",
                   o.out_dir, o.report ? fmt::format(", {}/report.html", o.out_dir) : "");
  return 0;
}

}  // namespace

Command add_csg_command(CLI::App& app) {
  auto o = std::make_shared<CsgOptions>();
  auto* cmd = app.add_subcommand(
      "csg",
      "The parity and depth-interval applications (Rossignac 9.2.2 to 9.2.4) on the machine, each "
      "against a double-precision ground truth (--application, all by default): parity, point "
      "in solid (parity, parity_accurate); epsilon, the erosion (parity_epsilon) and the test "
      "at z + epsilon (parity_behind) beside exact parity; interference of two solids by depth "
      "intervals "
      "(interference, interference_accurate); csg, CSG rendering by Goldfeather's multipass "
      "algorithm over meshes and quadric spheres (csg, csg_accurate, csg_layers); "
      "transparency, front to back and back to front with a depth-interval buffer "
      "(transparent, transparent_interval) against every layer composited; section, a solid "
      "cut by a plane and capped by parity (section, section_accurate). The ray caster sees "
      "the same solids and expression. Prints the agreement tables (pixels disagreeing, "
      "passes, bits, Renderer cycles, frame time) and writes each image and an image of the "
      "differing pixels (white; grey: near an edge, not compared).");
  cmd->add_option("-s,--scene", o->scenes,
                  "A parity scene (repeatable): plane-sphere, "
                  "plane-boxes; default both");
  cmd->add_option("-p,--program", o->programs,
                  "A program defining 'parity' (repeatable); default parity and parity_accurate");
  cmd->add_option("-a,--assembly", o->assemblies,
                  "An assembly scene for interference (repeatable): boxes-overlap, boxes-apart, "
                  "boxes-touching; default all three");
  cmd->add_option("--interference", o->interference,
                  "An interference program (repeatable; default interference and "
                  "interference_accurate)");
  cmd->add_option("--csg-scene", o->csg_scenes,
                  "A CSG scene to render (repeatable): box-minus-ball, ball-and-ball, "
                  "box-or-ball, box-minus-two, pair-minus-bar, and box-minus-quadric and "
                  "quadric-lens (quadric spheres as solids: only programs with sphere_surface "
                  "draw them); default all seven");
  cmd->add_option(
      "--csg-program", o->csg_programs,
      "A program defining 'surface' (repeatable; default csg, csg_accurate and csg_layers)");
  cmd->add_option("--pruning-program", o->pruning_program,
                  "The program whose CSG pass plan is measured with and without Goldfeather's "
                  "pruning (default csg), on the mesh CSG scenes and box-minus-apart");
  cmd->add_option("--epsilon-program", o->epsilon_programs,
                  "A program defining 'parity' for the epsilon table (repeatable; default "
                  "parity, parity_epsilon (erosion) and parity_behind (the test at z + epsilon)); "
                  "scenes plane-sphere, plane-boxes, plane-slab, plane-in-box");
  cmd->add_option("--transparency-scene", o->transparency_scenes,
                  "A scene for transparency (repeatable): a built-in name, a mesh file or a scene "
                  "file; default torus");
  cmd->add_option("--transparency-program", o->transparency_programs,
                  "A transparency program (repeatable; default transparent and "
                  "transparent_interval)");
  cmd->add_option("--layers", o->layers,
                  "The transparency runs' layer counts (frame parameter `layers`, repeatable; "
                  "default 2, 4 and 8)")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--opacity", o->opacity,
                  "The opacity given to a transparency scene whose every surface is opaque (a "
                  "built-in one; default 0.5)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--section-scene", o->section_scenes,
                  "A cross-section scene (repeatable): section-sphere, section-torus; default "
                  "both");
  cmd->add_option("--section-program", o->section_programs,
                  "A cross-section program defining 'parity' (repeatable; default section and "
                  "section_accurate)");
  cmd->add_option(
         "--application", o->application,
         "parity, epsilon (the two epsilon regularisations), interference, csg (rendering), "
         "transparency, section or all (default all)")
      ->check(CLI::IsMember(
          {"parity", "epsilon", "interference", "csg", "transparency", "section", "all"}));
  add_config_options(*cmd, o->config_path, o->sets);
  cmd->add_option("-o,--out", o->out_dir, "Output folder (default out/csg)");
  add_report_flag(*cmd, o->report, "OUT");
  cmd->add_option("-j,--threads", o->threads, "Host threads (results are identical for any)")
      ->check(CLI::Range(1, 256));
  return {cmd, [o] { return run_csg(*o); }};
}

}  // namespace pp5
