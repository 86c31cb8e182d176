#include "sim/output/output_set.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <set>

namespace fs = std::filesystem;

namespace pp5 {

namespace {

// Temporaries the signal handler removes: fixed storage, written before a slot is marked in
// use and read by the handler only through async-signal-safe calls.
constexpr int kSlots = 64;
struct Slot {
  std::atomic<bool> used{false};
  char path[PATH_MAX + 1] = {};
};
std::array<Slot, kSlots> g_slots;

int register_temporary(const std::string& path) {
  if (path.size() > PATH_MAX) return -1;
  for (int k = 0; k < kSlots; ++k) {
    if (g_slots[k].used.load()) continue;
    std::memcpy(g_slots[k].path, path.c_str(), path.size() + 1);
    g_slots[k].used.store(true);
    return k;
  }
  return -1;  // more than kSlots at once: not removed on a signal, still removed on failure
}

void release_temporary(int slot) {
  if (slot >= 0) g_slots[slot].used.store(false);
}

extern "C" void remove_temporaries_and_reraise(int signal) {
  for (Slot& s : g_slots) {
    if (s.used.load()) ::unlink(s.path);
  }
  // SA_RESETHAND has restored the default action: end the process as the signal would.
  ::raise(signal);
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
  const int fd = ::mkstemp(tmpl.data());
  if (fd < 0) {
    throw OutputError(path + ": cannot create a temporary file beside it (" + reason(errno) + ")");
  }
  slot = register_temporary(tmpl);
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

}  // namespace

void OutputSet::add(const std::string& path, std::string bytes) {
  outputs_.push_back({path, std::move(bytes)});
}

void OutputSet::commit() {
  // Every destination is checked before anything is written.
  std::set<std::string> seen;
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
    const std::string key = fs::weakly_canonical(dest, ec).string();
    if (!seen.insert(ec ? o.path : key).second) {
      throw OutputError(o.path + ": named twice among this run's outputs");
    }
  }
  std::vector<std::string> temporaries;
  std::vector<int> slots;
  auto discard = [&] {
    for (std::size_t k = 0; k < temporaries.size(); ++k) {
      ::unlink(temporaries[k].c_str());
      release_temporary(slots[k]);
    }
  };
  try {
    for (const Output& o : outputs_) {
      int slot = -1;
      temporaries.push_back(write_temporary(o.path, o.bytes, slot));
      slots.push_back(slot);
    }
  } catch (...) {
    discard();
    throw;
  }
  // Every output is written: now they replace the old ones. rename() within a folder is
  // atomic, and the checks above leave only rare failures here (the destination made a
  // folder meanwhile); then the remaining temporaries are removed and the error names it.
  for (std::size_t k = 0; k < outputs_.size(); ++k) {
    if (std::rename(temporaries[k].c_str(), outputs_[k].path.c_str()) != 0) {
      const int err = errno;
      for (std::size_t j = k; j < temporaries.size(); ++j) ::unlink(temporaries[j].c_str());
      for (int s : slots) release_temporary(s);
      throw OutputError(outputs_[k].path + ": cannot move into place (" + reason(err) + ")");
    }
    release_temporary(slots[k]);
  }
  outputs_.clear();
}

void write_file_atomically(const std::string& path, const std::string& text) {
  OutputSet one;
  one.add(path, text);
  one.commit();
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
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction action {};
    action.sa_handler = remove_temporaries_and_reraise;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND;
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
}

}  // namespace pp5
