// Loads libpp5_assimp.so on first use (sim/scene/assimp_reader.hpp).
#include <dlfcn.h>
#include <fmt/format.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

#include "sim/scene/assimp_reader.hpp"
#include "sim/scene/mesh_loader.hpp"

namespace pp5 {

namespace {

namespace fs = std::filesystem;
constexpr const char* kModule = "libpp5_assimp.so";

using Factory = AssimpReader* (*)();

struct Loaded {
  Factory factory = nullptr;
  std::string failure;  // why it could not be loaded, if it could not
};

Loaded load_module() {
  std::vector<fs::path> candidates;
  std::error_code error;
  if (const char* named = std::getenv("PP5_ASSIMP_MODULE"); named && *named) {
    // The one file to load (packagers, tests); a bare name is a file in the current folder,
    // not a search of the library path.
    candidates.push_back(fs::absolute(named, error));
  } else {
    const fs::path exe = fs::read_symlink("/proc/self/exe", error);
    if (!error) {
      // Installed (bin/../lib/pp5sim), then a build tree's own layout (build/pp5sim and
      // build/lib/pp5sim), which still holds when the build tree is moved.
      candidates.push_back((exe.parent_path() / PP5_MODULE_FROM_BIN / kModule).lexically_normal());
      candidates.push_back(exe.parent_path() / "lib" / "pp5sim" / kModule);
    }
    candidates.push_back(fs::path(PP5_MODULE_BUILD_DIR) / kModule);
  }
  Loaded loaded;
  std::string tried;
  for (const fs::path& path : candidates) {
    if (!fs::exists(path, error)) {
      tried += fmt::format("{}{} (absent)", tried.empty() ? "" : ", ", path.string());
      continue;
    }
    // dlopen would wait forever on a FIFO, and read a device to no end.
    if (!fs::is_regular_file(path, error)) {
      tried += fmt::format("{}{} (not a regular file)", tried.empty() ? "" : ", ", path.string());
      continue;
    }
    // Never closed: its code may be running in any reader until the process ends.
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      tried += fmt::format("{}{} ({})", tried.empty() ? "" : ", ", path.string(), dlerror());
      continue;
    }
    loaded.factory = reinterpret_cast<Factory>(dlsym(handle, "pp5_new_assimp_reader"));
    if (loaded.factory) return loaded;
    tried +=
        fmt::format("{}{} (no pp5_new_assimp_reader)", tried.empty() ? "" : ", ", path.string());
  }
  loaded.failure = fmt::format(
      "reading a mesh file needs pp5sim's assimp module, {}, which could not be "
      "loaded; tried {}",
      kModule, tried);
  return loaded;
}

}  // namespace

std::unique_ptr<AssimpReader> open_assimp_reader() {
  static std::once_flag once;
  static Loaded loaded;
  std::call_once(once, [] { loaded = load_module(); });
  if (!loaded.factory) throw MeshError(loaded.failure);
  return std::unique_ptr<AssimpReader>(loaded.factory());
}

}  // namespace pp5
