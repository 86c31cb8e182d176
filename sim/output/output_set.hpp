#pragma once
// A run's output files, written all or none.
//
// Contract:
//  - add() collects each output's path and bytes; commit() first checks every destination
//    (its folder exists and is a folder, the path is not a folder, no two outputs share a
//    path), then writes each output to a temporary file of its own beside its destination,
//    named uniquely for this process and file (mkstemp), and only when every one is written
//    renames them all into place. A failure before the renames removes every temporary and
//    leaves every destination as it was; its message names the file and the OS reason
//    ("No space left on device", "Is a directory", ...).
//  - What the user named is what is written: a symbolic link is followed and its target
//    replaced (the link stays); a FIFO or a device (/dev/null, /dev/stdout, a terminal) is
//    written in place, after every temporary is ready and before the renames, never renamed
//    over. A socket is refused.
//  - The renames of one commit happen under an exclusive lock (flock) on each destination
//    folder, so two runs writing the same folder at once leave one run's complete set, never
//    a mix; SIGINT, SIGTERM or SIGHUP arriving during the renames takes effect after the last.
//  - While temporaries exist they are registered for removal on SIGINT, SIGTERM and SIGHUP
//    (install_signal_cleanup), so an interrupted run leaves no partial file behind; so are
//    the folders prepare_output_folder created, removed on a signal if still empty, until a
//    commit puts files in them.
#include <stdexcept>
#include <string>
#include <vector>

namespace pp5 {

struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class OutputSet {
 public:
  void add(const std::string& path, std::string bytes);
  void commit();
  bool empty() const { return outputs_.empty(); }

 private:
  struct Output {
    std::string path;
    std::string bytes;
  };
  std::vector<Output> outputs_;
};

// The default output folder of a run named `name`: out/NAME, with a name that is not a
// plain folder name ("", ".", "..", or one with a '/') replaced by "scene", so that a mesh file
// named "...obj" does not make the folder out/..
std::string default_output_folder(const std::string& name);

// Creates the folder `dir` (and its parents) if needed. A path that exists and is not a
// folder is an OutputError naming `option`. Returns whether the folder already holds a run's
// outputs (frame.png or stats.json), which this run will replace.
bool prepare_output_folder(const std::string& dir, const std::string& option);

// After a failed run: removes the folders prepare_output_folder created, innermost first,
// each only if it is still empty, so a run that writes nothing leaves no folder behind.
void remove_created_folders();

// Writes one file through OutputSet.
void write_file_atomically(const std::string& path, const std::string& text);

// Installs the handlers that remove registered temporaries on SIGINT, SIGTERM and SIGHUP and
// then end the process as the signal would have. Idempotent.
void install_signal_cleanup();

}  // namespace pp5
