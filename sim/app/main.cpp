// pp5sim: the command-line program. Each subcommand is in its own file (see commands.hpp).

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "common/escape.hpp"
#include "common/memory_note.hpp"
#include "sim/app/commands.hpp"
#include "sim/host_memory.hpp"
#include "sim/output/output_set.hpp"

namespace {

// Levenshtein distance, for "did you mean" on a mistyped command or option.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1])});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// The closest of `names` to `word`, if it is close enough to be a typo.
std::string closest(const std::string& word, const std::vector<std::string>& names) {
  std::string best;
  std::size_t best_distance = 3;  // at most two edits
  for (const std::string& n : names) {
    const std::size_t d = edit_distance(word, n);
    if (d < best_distance && d < std::max<std::size_t>(2, n.size() / 2)) {
      best = n;
      best_distance = d;
    }
  }
  return best;
}

// A parse error as a sentence with a suggestion, instead of CLI11's own exit codes (105-114).
int report_parse_error(const CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
  std::string hint;
  std::vector<std::string> commands;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    commands.push_back(sub->get_name());
  // The subcommand that was given, if any: its options are the ones to suggest.
  const CLI::App* active = &app;
  for (const CLI::App* sub : app.get_subcommands()) active = sub;
  std::vector<std::string> options;
  for (const CLI::Option* o : active->get_options()) {
    for (const std::string& name : o->get_lnames()) options.push_back("--" + name);
  }
  for (int k = 1; k < argc && hint.empty(); ++k) {
    const std::string word = argv[k];
    if (word.rfind("--", 0) == 0) {
      const std::string name = word.substr(0, word.find('='));
      if (std::find(options.begin(), options.end(), name) != options.end()) continue;
      const std::string near = closest(name, options);
      if (!near.empty()) hint = "unknown option '" + name + "'; did you mean '" + near + "'?";
    } else if (k == 1 && word[0] != '-' &&
               std::find(commands.begin(), commands.end(), word) == commands.end()) {
      const std::string near = closest(word, commands);
      hint =
          "unknown command '" + word + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?");
    }
  }
  std::cerr << "pp5sim: error: " << pp5::sanitize_message(hint.empty() ? e.what() : hint) << "\n"
            << "run 'pp5sim --help' (or 'pp5sim COMMAND --help') for the usage\n";
  return 2;
}

// The top-level --help: each command on one line. A command's own --help keeps its whole
// description; here it is cut to its first clause (before " (", ". " or "; ") and to the
// width of a terminal, so that a new command needs nothing added here.
class OneLineCommands : public CLI::Formatter {
 public:
  std::string make_subcommand(const CLI::App* sub) const override {
    std::string line = sub->get_description();
    for (const char* stop : {" (", ". ", "; ", ", each", ", then"}) {
      const auto at = line.find(stop);
      if (at != std::string::npos && at >= 12) line = line.substr(0, at);
    }
    constexpr std::size_t kWidth = 64;
    if (line.size() > kWidth) {
      const auto space = line.rfind(' ', kWidth - 4);
      line = line.substr(0, space == std::string::npos ? kWidth - 4 : space) + " ...";
    }
    char buffer[256];
    std::snprintf(buffer, sizeof buffer, "  %-13s %s\n", sub->get_name().c_str(), line.c_str());
    return buffer;
  }
  std::string make_footer(const CLI::App*) const override {
    return "\nRun 'pp5sim COMMAND --help' for a command's options and the files it writes.\n";
  }
};

// SystemC reports an exception thrown inside a simulation process as its own error, "Error:
// (E549) uncaught exception: MESSAGE\nIn file: kernel/sc_except.cpp:101\nIn process: ...":
// the user gets MESSAGE, which names the input, without the kernel's frame around it.
std::string unwrap_systemc_error(const std::string& what) {
  const std::string tag = "uncaught exception: ";
  const std::size_t at = what.find(tag);
  if (what.find("(E549)") == std::string::npos || at == std::string::npos) return what;
  std::string message = what.substr(at + tag.size());
  const std::size_t frame = message.find("\nIn file:");
  if (frame != std::string::npos) message.erase(frame);
  while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) message.pop_back();
  return message;
}

#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
#define PP5_SANITIZED 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define PP5_SANITIZED 1
#endif
#if defined(__linux__) && !defined(PP5_SANITIZED)
// Called from the executable's .preinit_array, which runs before any shared library's
// initialisers: SystemC's own start-up allocation (3 MB, zeroed by its static constructor,
// 768 page faults, about 15 ms of every run on the development machine) lands in the tuned
// heap too. Only C library calls, which are ready by then. Not under the sanitizers, whose
// runtimes own malloc and their own start-up.
void preinit(int, char**, char**) { pp5::tune_host_memory(); }

__attribute__((section(".preinit_array"), used)) void (*const preinit_entry)(int, char**,
                                                                             char**) = preinit;
#endif

}  // namespace

namespace pp5 {
extern const char* const kVersion;  // "0.10 (git describe)": version.cpp, made at build time
}  // namespace pp5

int main(int argc, char** argv) {
  using namespace pp5;
  CLI::App app{
      "pp5sim: a cycle-approximate simulator of the Pixel-Planes 5 graphics machine.\n"
      "With no subcommand it renders the built-in torus with the Phong firmware."};
  app.require_subcommand(0, 1);
  app.set_version_flag("--version", std::string("pp5sim ") + kVersion);

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
      add_validate_command(app),
      add_visible_command(app),
      add_fidelity_command(app),
      add_scanconvert_command(app),
      add_spheres_command(app),
      add_csg_command(app),
      add_animate_command(app),
  };

  // After the commands are added: they keep the default formatter, with full descriptions.
  app.formatter(std::make_shared<OneLineCommands>());
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return report_parse_error(app, e, argc, argv);
  }
  // An interrupted run removes the temporary files of its outputs (sim/output).
  install_signal_cleanup();

  try {
    for (const auto& command : commands) {
      if (*command.app) return command.run();
    }
    return render.run();  // no subcommand: render with the defaults
  } catch (const std::bad_alloc&) {
    remove_created_folders();
    std::cerr << "pp5sim: error: out of memory: the run needs more memory than the host could "
                 "give; "
              << memory_note() << (memory_note().empty() ? "" : "; ")
              << "make the scene, the screen, renderer.backing_store_bits or the sweep "
                 "smaller\n";
    return 1;
  } catch (const std::exception& e) {
    remove_created_folders();  // a failed run leaves no empty output folder
    // SystemC reports an exception thrown inside a simulation process as its own error
    // (E549, "uncaught exception"), naming the original: bad_alloc is still out of memory.
    if (std::string(e.what()).find("bad_alloc") != std::string::npos) {
      std::cerr << "pp5sim: error: out of memory during the simulation; " << memory_note()
                << (memory_note().empty() ? "" : "; ")
                << "make the scene, the screen or renderer.backing_store_bits smaller\n";
      return 1;
    }
    // Escaped and cut short here too, whatever the message took from an input.
    std::cerr << "pp5sim: error: " << sanitize_message(unwrap_systemc_error(e.what())) << "\n";
    return 1;
  }
}
