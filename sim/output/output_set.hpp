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
#include <cstddef>
#include <set>
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

// A run's output files written as the run goes, all or none: the outputs of a long run
// (pp5sim animate, render --frames) are not held in memory until the end.
//
// Contract:
//  - stage(path) returns the name of a file to write now, in a staging folder of this run:
//    ".pp5-staging-PID-XXXXXX" (the process id and a random suffix, mkdtemp) made inside the
//    folder `path` goes to (the folder of a symbolic link's target: what the user named is
//    what is written, as OutputSet), so that no other run shares it and the final move is a
//    rename within one file system. The destination is checked then (its folder exists, it
//    is not a folder, not a socket, not named twice).
//  - add(path, bytes) stages and writes a file at once; StagedFile appends to a staged file
//    piece by piece. A failure (a full disk, a file-size limit, a folder that cannot be
//    written) is an OutputError naming the destination file and the OS reason.
//  - commit() moves every staged file into place, under a lock on each destination folder and
//    with SIGINT, SIGTERM and SIGHUP held until the last move (as OutputSet), writes FIFOs
//    and devices in place, then removes the staging folders. Without a commit (an error, an
//    exception, the destructor, discard()) every staging folder is removed with all it
//    holds and no destination is touched.
//  - Each staging folder is registered for removal on SIGINT, SIGTERM and SIGHUP from the
//    moment it exists (install_signal_cleanup): a run interrupted at any point leaves none.
class StagedOutputs {
 public:
  StagedOutputs() = default;
  ~StagedOutputs();
  StagedOutputs(const StagedOutputs&) = delete;
  StagedOutputs& operator=(const StagedOutputs&) = delete;

  std::string stage(const std::string& path);
  // The name of a scratch file in the staging folder of `staged` (a name stage() gave):
  // written during the run, never moved into place, removed with the staging folder.
  std::string scratch(const std::string& staged, const std::string& name);
  // Returns the staged file's name (to read it back before the commit).
  std::string add(const std::string& path, const std::string& bytes);
  void commit();
  void discard();

 private:
  struct Staged {
    std::string path;    // as named
    std::string target;  // what the name leads to (a link followed)
    std::string staged;  // the file in the staging folder
    bool in_place = false;
  };
  struct Folder {
    std::string dir;      // the destination folder
    std::string staging;  // its staging folder
    int slot = -1;        // its signal-cleanup registration
  };
  std::vector<Staged> files_;
  std::set<std::string> targets_;  // the files_' targets (not in place): no name twice
  std::vector<Folder> folders_;
  int scratches_ = 0;
  const Folder& folder_for(const std::string& dir);
};

// The bytes of a staged file `staged` (a name stage() or add() gave), read back before the
// commit (a report embedding them, a FIFO written at commit); errors name `path`.
std::string read_staged(const std::string& staged, const std::string& path);

// A staged file written piece by piece (StagedOutputs::stage); errors name `path`, the
// destination. close() (or the destructor) closes it; writing after an error throws again.
class StagedFile {
 public:
  StagedFile(StagedOutputs& outputs, const std::string& path);
  // A scratch file (StagedOutputs::scratch) `file`, whose errors name `path`.
  StagedFile(const std::string& file, const std::string& path);
  ~StagedFile();
  StagedFile(const StagedFile&) = delete;
  StagedFile& operator=(const StagedFile&) = delete;
  void write(const std::string& bytes) { write(bytes.data(), bytes.size()); }
  void write(const char* data, std::size_t size);
  void close();
  const std::string& staged_path() const { return staged_; }

 private:
  std::string path_, staged_;
  int fd_ = -1;
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
