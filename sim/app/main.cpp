// pp5sim: the command-line program. Each subcommand is in its own file (see commands.hpp).
#include <CLI/CLI.hpp>
#include <iostream>

#include "sim/app/commands.hpp"

int main(int argc, char** argv) {
  using namespace pp5;
  CLI::App app{
      "pp5sim: a cycle-approximate simulator of the Pixel-Planes 5 graphics machine.\n"
      "With no subcommand it renders the built-in torus with the Phong firmware."};
  app.require_subcommand(0, 1);

  const Command render = add_render_command(app);
  const std::vector<Command> commands = {
      render,
      add_isa_command(app),
      add_asm_command(app),
      add_config_command(app),
      add_stats_command(app),
      add_scenes_command(app),
      add_sweep_command(app),
      add_trace_command(app),
      add_highlight_command(app),
      add_extremes_command(app),
  };

  CLI11_PARSE(app, argc, argv);

  try {
    for (const auto& command : commands) {
      if (*command.app) return command.run();
    }
    return render.run();  // no subcommand: render with the defaults
  } catch (const std::exception& e) {
    std::cerr << "pp5sim: error: " << e.what() << "\n";
    return 1;
  }
}
