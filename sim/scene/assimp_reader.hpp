#pragma once
// assimp behind one small interface, in a module of its own (libpp5_assimp.so), loaded the
// first time a mesh file is read. Loading assimp and the libraries it needs costs a process
// about 9 ms before main() (43,000 relocations, BIND_NOW; measured on the development
// machine with perf stat against an empty program), and most runs read no mesh file: the
// built-in scenes, scene files without meshes, molecules, programs and traces do not.
//
// Contract:
//  - open_assimp_reader() loads the module once per process (thread-safe) and returns a new
//    reader; if the module cannot be found or loaded it throws MeshError naming the paths it
//    tried and the loader's message. It looks next to the executable (installed layout:
//    bin/../lib/pp5sim, PP5_MODULE_FROM_BIN), beside it as a build tree lays it out
//    (lib/pp5sim), and then in the build tree it was built in; the
//    environment variable PP5_ASSIMP_MODULE, if set, names the one file to load instead.
//  - A reader reads one file: read(), then meshes(). It throws nothing; failures come back
//    as false with assimp's message.
//  - The meshes are what assimp made, unchecked: the caller (mesh_loader.cpp) checks every
//    index and number before it uses them, and joins identical corners itself (exactly:
//    assimp's JoinIdenticalVertices merges within an epsilon).
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace pp5 {

// One of assimp's meshes, copied out of its scene.
struct ImportedMesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec4> colors;          // per vertex; empty when the file has none
  std::vector<std::uint32_t> face_sizes;  // corners of each face
  std::vector<std::uint32_t> indices;     // the faces' corners, face after face
};

class AssimpReader {
 public:
  virtual ~AssimpReader() = default;
  // Reads `data` in `format` ("obj", "ply", "stl", "off") with that format's importer alone,
  // opening no other file. False, with `error` set, if assimp refuses it; its in-memory file
  // is called "the file" in the message.
  virtual bool read(std::string_view data, const std::string& format, std::string& error) = 0;
  virtual std::vector<ImportedMesh> meshes() const = 0;
};

std::unique_ptr<AssimpReader> open_assimp_reader();

// The layout of the interface above (AssimpReader, ImportedMesh): raised whenever it changes,
// so that a module of another build is refused rather than called.
inline constexpr int kAssimpReaderInterface = 1;

}  // namespace pp5

// The module's entry points (C linkage, for dlsym): the interface it implements, and a new
// reader, owned by the caller.
extern "C" const int pp5_assimp_reader_interface;
extern "C" pp5::AssimpReader* pp5_new_assimp_reader();
