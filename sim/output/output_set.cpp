#include "sim/output/output_set.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <set>
#include <thread>

#include "common/read_file.hpp"

namespace fs = std::filesystem;

namespace pp5 {

namespace {

// Temporaries the signal handler removes, and folders it removes if they are still empty:
// fixed storage, written before a slot is marked in use and read by the handler only through
// async-signal-safe calls.
constexpr int kSlots = 64;
struct Slot {
  std::atomic<bool> used{false};
  char path[PATH_MAX + 1] = {};
};
std::array<Slot, kSlots> g_slots;
std::array<Slot, kSlots> g_folder_slots;   // outermost first
std::array<Slot, kSlots> g_staging_slots;  // staging folders, removed with what they hold
// While a commit moves a run's files into place (or a temporary is created and registered),
// a signal waits for it to finish (the handler records it and returns), so that a run's
// files appear together or not at all and no temporary escapes the handler.
std::atomic<bool> g_committing{false};
std::atomic<int> g_pending_signal{0};

int register_path(std::array<Slot, kSlots>& slots, const std::string& path) {
  if (path.size() > PATH_MAX) return -1;
  for (int k = 0; k < kSlots; ++k) {
    if (slots[k].used.load()) continue;
    std::memcpy(slots[k].path, path.c_str(), path.size() + 1);
    slots[k].used.store(true);
    return k;
  }
  return -1;  // more than kSlots at once: not removed on a signal, still removed on failure
}

int register_temporary(const std::string& path) { return register_path(g_slots, path); }

void release_temporary(int slot) {
  if (slot >= 0) g_slots[slot].used.store(false);
}

// Removes the files in the folder `path` (a staging folder holds files only), then the
// folder: async-signal-safe calls only (open, the getdents64 system call, unlinkat, rmdir).
void remove_staging_folder(const char* path) {
  const int fd = ::open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    alignas(8) char buffer[4096];
    for (bool removed = true; removed;) {  // until a pass removes nothing
      removed = false;
      const long n = ::syscall(SYS_getdents64, fd, buffer, sizeof buffer);
      if (n <= 0) break;
      for (long at = 0; at < n;) {
        // struct linux_dirent64: d_ino (8), d_off (8), d_reclen (2), d_type (1), d_name.
        unsigned short length;
        std::memcpy(&length, buffer + at + 16, sizeof length);
        const char* name = buffer + at + 19;
        if (!(name[0] == '.' && (name[1] == '\0' || (name[1] == '.' && name[2] == '\0'))))
          removed = ::unlinkat(fd, name, 0) == 0 || removed;
        at += length;
      }
      // Entries removed while reading: read the folder again from its start.
      ::lseek(fd, 0, SEEK_SET);
    }
    ::close(fd);
  }
  ::rmdir(path);
}

// Removes the registered temporaries and staging folders, then the registered folders
// innermost first (rmdir removes only an empty folder, so never one that holds another run's
// files).
void remove_registered() {
  for (Slot& s : g_slots) {
    if (s.used.load()) ::unlink(s.path);
  }
  for (Slot& s : g_staging_slots) {
    if (s.used.load()) remove_staging_folder(s.path);
  }
  for (int k = kSlots; k-- > 0;) {
    if (g_folder_slots[k].used.load()) ::rmdir(g_folder_slots[k].path);
  }
}

extern "C" void remove_temporaries_and_reraise(int signal) {
  if (g_committing.load()) {
    g_pending_signal.store(signal);
    return;
  }
  remove_registered();
  // End the process as the signal would have.
  struct sigaction action {};
  action.sa_handler = SIG_DFL;
  sigemptyset(&action.sa_mask);
  ::sigaction(signal, &action, nullptr);
  ::raise(signal);
}

void forget_created_folders() {
  for (Slot& s : g_folder_slots) s.used.store(false);
}

// After a commit: a signal that came during it now takes effect (the run's files are all in
// place, so only folders and temporaries of later outputs are removed).
void end_commit() {
  g_committing.store(false);
  const int signal = g_pending_signal.exchange(0);
  if (signal != 0) remove_temporaries_and_reraise(signal);
}

// Test hook: PP5_TEST_COMMIT_PAUSE_MS=N pauses N ms between two renames of a commit, so that
// tests can send a signal, or run a second commit, exactly there. Unset in normal use.
void test_pause_between_renames() {
  static const char* pause = std::getenv("PP5_TEST_COMMIT_PAUSE_MS");
  if (pause == nullptr) return;
  std::this_thread::sleep_for(std::chrono::milliseconds(std::atoi(pause)));
}

std::string reason(int err) { return std::strerror(err); }

// Creates a unique temporary beside `path`, writes `bytes`, closes it; returns its name.
std::string write_temporary(const std::string& path, const std::string& bytes, int& slot) {
  const fs::path dest(path);
  const fs::path dir = dest.parent_path().empty() ? fs::path(".") : dest.parent_path();
  // ".NAME.XXXXXX", unless the name is so long that the suffix would not fit a file name.
  std::string name = "." + dest.filename().string() + ".XXXXXX";
  if (name.size() > NAME_MAX) name = ".pp5-output.XXXXXX";
  std::string tmpl = (dir / name).string();
  // A signal between mkstemp and the registration would leave the new file behind: it waits
  // (as during a commit's renames) until the file is registered.
  g_committing.store(true);
  const int fd = ::mkstemp(tmpl.data());
  const int create_errno = errno;
  if (fd >= 0) slot = register_temporary(tmpl);
  end_commit();
  if (fd < 0) {
    throw OutputError(path + ": cannot create a temporary file beside it (" + reason(create_errno) +
                      ")");
  }
  auto fail = [&](const std::string& what, int err) {
    ::close(fd);
    ::unlink(tmpl.c_str());
    release_temporary(slot);
    slot = -1;
    throw OutputError(path + ": " + what + " (" + reason(err) + ")");
  };
  // mkstemp creates 0600; outputs are ordinary files, readable as the umask allows.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  if (::fchmod(fd, 0666 & ~mask) != 0) fail("cannot set the file's mode", errno);
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail("cannot write", errno);
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmpl.c_str());
    release_temporary(slot);
    slot = -1;
    throw OutputError(path + ": cannot write (" + reason(err) + ")");
  }
  return tmpl;
}

// Where an output's bytes go. A regular file, or a name not yet taken, is replaced through a
// temporary and a rename. A symbolic link is followed (as a shell's '>' would) and its final
// target is treated the same way, so the link stays a link. Anything else (a FIFO, a device
// such as /dev/null, a terminal) is written in place: renaming over it would replace the
// node the user named with a regular file.
struct Target {
  std::string path;       // the file to write or replace
  bool in_place = false;  // write into the existing node rather than rename over it
};

Target resolve_output_target(const std::string& named) {
  // What the name leads to, links followed: a link to a FIFO, a device or a pipe
  // (/dev/stdout is /proc/self/fd/1, whose target "pipe:[N]" is no path) is written in place
  // through the name itself.
  {
    struct stat st {};
    if (::stat(named.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
      if (S_ISDIR(st.st_mode)) throw OutputError(named + ": is a folder, expected a file to write");
      if (S_ISSOCK(st.st_mode))
        throw OutputError(named + ": is a socket, expected a file, a FIFO or a device to write");
      return {named, true};
    }
    if (errno == ELOOP) throw OutputError(named + ": too many levels of symbolic links");
  }
  fs::path p(named);
  for (int hops = 0;; ++hops) {
    struct stat st {};
    if (::lstat(p.c_str(), &st) != 0) {
      if (errno == ENOENT) return {p.string(), false};
      throw OutputError(named + ": cannot look at the file (" + reason(errno) + ")");
    }
    if (S_ISREG(st.st_mode)) return {p.string(), false};
    if (S_ISDIR(st.st_mode)) throw OutputError(named + ": is a folder, expected a file to write");
    if (!S_ISLNK(st.st_mode)) {
      if (S_ISSOCK(st.st_mode))
        throw OutputError(named + ": is a socket, expected a file, a FIFO or a device to write");
      return {p.string(), true};
    }
    if (hops == 40) throw OutputError(named + ": too many levels of symbolic links");
    std::error_code ec;
    const fs::path link = fs::read_symlink(p, ec);
    if (ec) throw OutputError(named + ": cannot read the link (" + ec.message() + ")");
    p = link.is_absolute() ? link : p.parent_path() / link;
  }
}

// Writes `bytes` into the existing node `path` (a FIFO or a device). No temporary: opening a
// FIFO waits for a reader, as a shell's '>' does.
void write_in_place(const std::string& named, const std::string& path, const std::string& bytes) {
  int fd;
  do {
    fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY);
  } while (fd < 0 && errno == EINTR);
  if (fd < 0) throw OutputError(named + ": cannot open for writing (" + reason(errno) + ")");
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : EIO;
      ::close(fd);
      throw OutputError(named + ": cannot write (" + reason(err) + ")");
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0 && errno != EINTR) {
    throw OutputError(named + ": cannot write (" + reason(errno) + ")");
  }
}

// An exclusive lock on a folder, held while a commit moves its files into place: two runs
// writing the same folder move their sets one after the other, never interleaved.
struct FolderLock {
  int fd = -1;
  explicit FolderLock(const std::string& dir) {
    fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return;  // no lock (e.g. no read permission): the rename is still atomic
    while (::flock(fd, LOCK_EX) != 0 && errno == EINTR) {
    }
  }
  ~FolderLock() {
    if (fd >= 0) ::close(fd);  // releases the lock
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
};

}  // namespace

void OutputSet::add(const std::string& path, std::string bytes) {
  outputs_.push_back({path, std::move(bytes)});
}

void OutputSet::commit() {
  // Every destination is checked before anything is written.
  std::set<std::string> seen;
  std::vector<Target> targets;
  for (const Output& o : outputs_) {
    const fs::path dest(o.path);
    if (dest.filename().empty()) throw OutputError(o.path + ": expected a file name, not a folder");
    const fs::path dir = dest.parent_path().empty() ? fs::path(".") : dest.parent_path();
    std::error_code ec;
    const fs::file_status ds = fs::status(dir, ec);
    if (!fs::exists(ds))
      throw OutputError(o.path + ": the folder " + dir.string() + " does not exist");
    if (!fs::is_directory(ds)) throw OutputError(o.path + ": " + dir.string() + " is not a folder");
    if (fs::is_directory(fs::status(dest, ec))) {
      throw OutputError(o.path + ": is a folder, expected a file to write");
    }
    targets.push_back(resolve_output_target(o.path));
    const Target& t = targets.back();
    if (!t.in_place) {
      const fs::path tdir =
          fs::path(t.path).parent_path().empty() ? fs::path(".") : fs::path(t.path).parent_path();
      if (!fs::is_directory(tdir, ec)) {
        throw OutputError(o.path + ": links to " + t.path + ", whose folder does not exist");
      }
    }
    const std::string key = fs::weakly_canonical(t.path, ec).string();
    if (!t.in_place && !seen.insert(ec ? t.path : key).second) {
      throw OutputError(o.path + ": named twice among this run's outputs");
    }
  }
  std::vector<std::string> temporaries(outputs_.size());
  std::vector<int> slots(outputs_.size(), -1);
  auto discard = [&] {
    for (std::size_t k = 0; k < temporaries.size(); ++k) {
      if (!temporaries[k].empty()) ::unlink(temporaries[k].c_str());
      release_temporary(slots[k]);
    }
  };
  try {
    for (std::size_t k = 0; k < outputs_.size(); ++k) {
      if (targets[k].in_place) continue;
      temporaries[k] = write_temporary(targets[k].path, outputs_[k].bytes, slots[k]);
    }
    // Outputs that cannot be replaced atomically (a FIFO, a device) are written once every
    // other one is ready, so that a failure among the others writes none of them.
    for (std::size_t k = 0; k < outputs_.size(); ++k) {
      if (targets[k].in_place) write_in_place(outputs_[k].path, targets[k].path, outputs_[k].bytes);
    }
  } catch (...) {
    discard();
    throw;
  }
  // Every output is written: now they replace the old ones, under a lock on each folder
  // (taken in one order, so two commits cannot deadlock) and with signals held until the
  // last rename. rename() within a folder is atomic, and the checks above leave only rare
  // failures here (the destination made a folder meanwhile); then the remaining temporaries
  // are removed and the error names it.
  std::set<std::string> folders;
  for (std::size_t k = 0; k < outputs_.size(); ++k) {
    if (targets[k].in_place) continue;
    const fs::path dir = fs::path(targets[k].path).parent_path();
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(dir.empty() ? fs::path(".") : dir, ec);
    folders.insert(ec ? dir.string() : canonical.string());
  }
  std::vector<std::unique_ptr<FolderLock>> locks;
  for (const std::string& dir : folders) locks.push_back(std::make_unique<FolderLock>(dir));
  g_committing.store(true);
  bool paused = false;
  for (std::size_t k = 0; k < outputs_.size(); ++k) {
    if (targets[k].in_place) continue;
    if (paused) test_pause_between_renames();
    paused = true;
    if (std::rename(temporaries[k].c_str(), targets[k].path.c_str()) != 0) {
      const int err = errno;
      for (std::size_t j = k; j < temporaries.size(); ++j) {
        if (!temporaries[j].empty()) ::unlink(temporaries[j].c_str());
      }
      for (int s : slots) release_temporary(s);
      locks.clear();
      end_commit();
      throw OutputError(outputs_[k].path + ": cannot move into place (" + reason(err) + ")");
    }
    release_temporary(slots[k]);
  }
  locks.clear();
  outputs_.clear();
  // The run's files are in place: its folders hold them and are no longer a signal's to remove.
  forget_created_folders();
  end_commit();
}

void write_file_atomically(const std::string& path, const std::string& text) {
  OutputSet one;
  one.add(path, text);
  one.commit();
}

namespace {

// Writes all of `data` to `fd`; false with errno set on failure.
bool staged_write_all(int fd, const char* data, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return false;
    if (n == 0) {
      errno = EIO;
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  return true;
}

std::string staged_folder_of(const std::string& path) {
  const fs::path dir = fs::path(path).parent_path();
  return dir.empty() ? std::string(".") : dir.string();
}

}  // namespace

StagedOutputs::~StagedOutputs() { discard(); }

const StagedOutputs::Folder& StagedOutputs::folder_for(const std::string& dir) {
  for (const Folder& f : folders_) {
    if (f.dir == dir) return f;
  }
  Folder f;
  f.dir = dir;
  std::string tmpl =
      (fs::path(dir) / (".pp5-staging-" + std::to_string(::getpid()) + "-XXXXXX")).string();
  // Registered as it is made: a signal between mkdtemp and the registration waits for it.
  g_committing.store(true);
  const char* made = ::mkdtemp(tmpl.data());
  const int err = errno;
  if (made != nullptr) f.slot = register_path(g_staging_slots, tmpl);
  end_commit();
  if (made == nullptr) {
    throw OutputError(dir + ": cannot create a staging folder for this run's outputs (" +
                      reason(err) + ")");
  }
  f.staging = tmpl;
  folders_.push_back(std::move(f));
  return folders_.back();
}

std::string StagedOutputs::stage(const std::string& path) {
  const fs::path dest(path);
  if (dest.filename().empty()) throw OutputError(path + ": expected a file name, not a folder");
  const std::string dir = staged_folder_of(path);
  std::error_code ec;
  const fs::file_status ds = fs::status(dir, ec);
  if (!fs::exists(ds)) throw OutputError(path + ": the folder " + dir + " does not exist");
  if (!fs::is_directory(ds)) throw OutputError(path + ": " + dir + " is not a folder");
  if (fs::is_directory(fs::status(dest, ec))) {
    throw OutputError(path + ": is a folder, expected a file to write");
  }
  const Target t = resolve_output_target(path);
  const std::string key = fs::weakly_canonical(t.path, ec).string();
  if (!t.in_place && targets_.count(ec ? t.path : key) != 0)
    throw OutputError(path + ": named twice among this run's outputs");
  // A FIFO or a device is written in place at commit; its bytes wait in the system's
  // temporary folder (no staging folder can be made beside /dev/stdout).
  const std::string staging_dir =
      t.in_place ? fs::temp_directory_path(ec).string() : staged_folder_of(t.path);
  if (!t.in_place && !fs::is_directory(staging_dir, ec))
    throw OutputError(path + ": links to " + t.path + ", whose folder does not exist");
  const Folder& folder = folder_for(staging_dir.empty() ? std::string("/tmp") : staging_dir);
  Staged f;
  f.path = path;
  f.target = t.in_place ? t.path : (ec ? t.path : key);
  f.in_place = t.in_place;
  // The staged file's name: its destination's, numbered when two share a name.
  f.staged = (fs::path(folder.staging) /
              ("out-" + std::to_string(files_.size()) + "-" + fs::path(t.path).filename().string()))
                 .string();
  if (f.staged.size() > PATH_MAX || fs::path(f.staged).filename().string().size() > NAME_MAX)
    f.staged = (fs::path(folder.staging) / std::to_string(files_.size())).string();
  if (!f.in_place) targets_.insert(f.target);
  files_.push_back(f);
  return files_.back().staged;
}

std::string StagedOutputs::scratch(const std::string& staged, const std::string& name) {
  return (fs::path(staged).parent_path() / ("scratch-" + std::to_string(scratches_++) + "-" + name))
      .string();
}

std::string StagedOutputs::add(const std::string& path, const std::string& bytes) {
  StagedFile file(*this, path);
  file.write(bytes);
  file.close();
  return file.staged_path();
}

void StagedOutputs::discard() {
  files_.clear();
  targets_.clear();
  for (Folder& f : folders_) {
    remove_staging_folder(f.staging.c_str());
    if (f.slot >= 0) g_staging_slots[f.slot].used.store(false);
  }
  folders_.clear();
}

void StagedOutputs::commit() {
  try {
    // FIFOs and devices first (as OutputSet: once every other output is ready).
    for (const Staged& f : files_) {
      if (!f.in_place) continue;
      write_in_place(f.path, f.target, read_staged(f.staged, f.path));
    }
  } catch (...) {
    discard();
    throw;
  }
  std::set<std::string> dirs;
  for (const Staged& f : files_) {
    if (f.in_place) continue;
    std::error_code ec;
    const fs::path dir = fs::path(f.target).parent_path();
    const fs::path canonical = fs::weakly_canonical(dir.empty() ? fs::path(".") : dir, ec);
    dirs.insert(ec ? dir.string() : canonical.string());
  }
  std::vector<std::unique_ptr<FolderLock>> locks;
  for (const std::string& dir : dirs) locks.push_back(std::make_unique<FolderLock>(dir));
  g_committing.store(true);
  bool paused = false;
  for (const Staged& f : files_) {
    if (f.in_place) continue;
    if (paused) test_pause_between_renames();
    paused = true;
    if (std::rename(f.staged.c_str(), f.target.c_str()) != 0) {
      const int err = errno;
      locks.clear();
      discard();
      end_commit();
      throw OutputError(f.path + ": cannot move into place (" + reason(err) + ")");
    }
  }
  locks.clear();
  // The run's files are in place: the staging folders (now holding only the bytes of FIFOs
  // and devices, already written) go, and the run's folders are no longer a signal's.
  discard();
  forget_created_folders();
  end_commit();
}

std::string read_staged(const std::string& staged, const std::string& path) {
  try {
    return read_regular_file(staged, std::numeric_limits<std::uint64_t>::max(), "a staged output");
  } catch (const FileError& e) {
    throw OutputError(path + ": cannot read back its staged bytes (" + e.what() + ")");
  }
}

StagedFile::StagedFile(StagedOutputs& outputs, const std::string& path)
    : StagedFile(outputs.stage(path), path) {}

StagedFile::StagedFile(const std::string& file, const std::string& path)
    : path_(path), staged_(file) {
  fd_ = ::open(staged_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd_ < 0) throw OutputError(path_ + ": cannot create (" + reason(errno) + ")");
}

StagedFile::~StagedFile() {
  if (fd_ >= 0) ::close(fd_);
}

void StagedFile::write(const char* data, std::size_t size) {
  if (fd_ < 0) throw OutputError(path_ + ": cannot write (the file is closed)");
  if (!staged_write_all(fd_, data, size)) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    throw OutputError(path_ + ": cannot write (" + reason(err) + ")");
  }
}

void StagedFile::close() {
  if (fd_ < 0) return;
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0 && errno != EINTR)
    throw OutputError(path_ + ": cannot write (" + reason(errno) + ")");
}

std::string default_output_folder(const std::string& name) {
  const bool plain = !name.empty() && name != "." && name != ".." &&
                     name.find('/') == std::string::npos && name.find('\0') == std::string::npos;
  return (fs::path("out") / (plain ? name : "scene")).string();
}

namespace {

// The folders prepare_output_folder made, outermost first.
std::vector<fs::path>& created_folders() {
  static std::vector<fs::path> folders;
  return folders;
}

}  // namespace

bool prepare_output_folder(const std::string& dir, const std::string& option) {
  std::error_code ec;
  const fs::file_status st = fs::status(dir, ec);
  if (fs::exists(st) && !fs::is_directory(st)) {
    throw OutputError(option + " " + dir + ": is a file, expected an output folder");
  }
  if (!fs::exists(st)) {
    std::vector<fs::path> missing;
    for (fs::path p = fs::path(dir).lexically_normal(); !p.empty() && !fs::exists(p, ec);
         p = p.parent_path()) {
      missing.push_back(p);
      if (p == p.parent_path()) break;
    }
    // Registered before they exist, so that a signal at any moment from here to the run's
    // commit removes them (rmdir: only if still empty).
    for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
      register_path(g_folder_slots, fs::absolute(*it, ec).string());
    }
    fs::create_directories(dir, ec);
    if (ec)
      throw OutputError(option + " " + dir + ": cannot create the folder (" + ec.message() + ")");
    created_folders().insert(created_folders().end(), missing.rbegin(), missing.rend());
    return false;
  }
  return fs::exists(fs::path(dir) / "frame.png", ec) ||
         fs::exists(fs::path(dir) / "stats.json", ec);
}

void install_signal_cleanup() {
  static std::atomic<bool> installed{false};
  if (installed.exchange(true)) return;
  // A file size limit (ulimit -f) makes write() fail with EFBIG, which the writer reports and
  // cleans up after, instead of SIGXFSZ ending the process with its folder half made.
  ::signal(SIGXFSZ, SIG_IGN);
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction action {};
    action.sa_handler = remove_temporaries_and_reraise;
    sigemptyset(&action.sa_mask);
    action.sa_flags = 0;  // the handler restores the default action itself
    ::sigaction(signal, &action, nullptr);
  }
}

void remove_created_folders() {
  std::vector<fs::path>& folders = created_folders();
  for (auto it = folders.rbegin(); it != folders.rend(); ++it) {
    std::error_code ec;
    if (fs::is_empty(*it, ec) && !ec) fs::remove(*it, ec);  // never one that holds a file
  }
  folders.clear();
  forget_created_folders();
}

}  // namespace pp5
