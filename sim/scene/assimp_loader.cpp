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
  std::string tried;  // each path looked at, and why it was passed over
  auto pass_over = [&tried](const fs::path& path, const std::string& why) {
    tried += fmt::format("{}{} ({})", tried.empty() ? "" : ", ", path.string(), why);
  };
  for (const fs::path& path : candidates) {
    if (!fs::exists(path, error)) {
      pass_over(path, "absent");
      continue;
    }
    // dlopen would wait forever on a FIFO, and read a device to no end.
    if (!fs::is_regular_file(path, error)) {
      pass_over(path, "not a regular file");
      continue;
    }
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      pass_over(path, dlerror());
      continue;
    }
    // A module of another build may lay the interface out differently: it must say it
    // implements this one (kAssimpReaderInterface).
    const auto* version = static_cast<const int*>(dlsym(handle, "pp5_assimp_reader_interface"));
    const auto factory = reinterpret_cast<Factory>(dlsym(handle, "pp5_new_assimp_reader"));
    if (version == nullptr || factory == nullptr) {
      pass_over(path, "not pp5sim's assimp module");
    } else if (*version != kAssimpReaderInterface) {
      pass_over(path, fmt::format("interface {}, this pp5sim needs {}", *version,
                                  kAssimpReaderInterface));
    } else {
      loaded.factory = factory;  // never closed: readers may run its code until the end
      return loaded;
    }
    dlclose(handle);
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
