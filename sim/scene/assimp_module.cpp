// libpp5_assimp.so: the only code that includes assimp (sim/scene/assimp_reader.hpp says why
// it is a module). Built as a CMake MODULE and loaded by open_assimp_reader().
#include <assimp/BaseImporter.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>
#include <cctype>
#include <exception>

#include "sim/scene/assimp_reader.hpp"

namespace pp5 {

namespace {

// assimp may read no file but the one in memory (an OBJ's "mtllib" names another file).
class NoFiles : public Assimp::IOSystem {
 public:
  bool Exists(const char*) const override { return false; }
  char getOsSeparator() const override { return '/'; }
  Assimp::IOStream* Open(const char*, const char*) override { return nullptr; }
  void Close(Assimp::IOStream* stream) override { delete stream; }
};

// An importer that knows only the one format, so that no other of assimp's importers
// guesses at the bytes.
void keep_only(Assimp::Importer& importer, const std::string& format) {
  const Assimp::BaseImporter* keep = importer.GetImporter(format.c_str());
  for (std::size_t i = importer.GetImporterCount(); i-- > 0;) {
    Assimp::BaseImporter* other = importer.GetImporter(i);
    if (other == keep) continue;
    importer.UnregisterLoader(other);
    delete other;  // UnregisterLoader hands it back to the caller
  }
}

class Reader : public AssimpReader {
 public:
  bool read(std::string_view data, const std::string& format, std::string& error) override {
    try {
      format_ = format;
      keep_only(importer_, format);
      importer_.SetIOHandler(new NoFiles);
      // No triangulation (mesh_loader.cpp's ear clipping handles concave faces); the import
      // is checked before any post-processing step runs on it.
      scene_ = importer_.ReadFileFromMemory(data.data(), data.size(), 0, format.c_str());
      if (!scene_) error = message();
      return scene_ != nullptr;
    } catch (const std::exception& e) {
      error = e.what();
      return false;
    }
  }

  std::vector<ImportedMesh> meshes() const override {
    std::vector<ImportedMesh> out;
    if (!scene_) return out;
    for (unsigned m = 0; m < scene_->mNumMeshes; ++m) {
      const aiMesh* mesh = scene_->mMeshes[m];
      ImportedMesh& o = out.emplace_back();
      o.positions.reserve(mesh->mNumVertices);
      for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
        const aiVector3D& p = mesh->mVertices[i];
        o.positions.emplace_back(p.x, p.y, p.z);
      }
      if (mesh->HasVertexColors(0)) {
        o.colors.reserve(mesh->mNumVertices);
        for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
          const aiColor4D& c = mesh->mColors[0][i];
          o.colors.emplace_back(c.r, c.g, c.b, c.a);
        }
      }
      o.face_sizes.reserve(mesh->mNumFaces);
      for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        const aiFace& face = mesh->mFaces[f];
        o.face_sizes.push_back(face.mNumIndices);
        o.indices.insert(o.indices.end(), face.mIndices, face.mIndices + face.mNumIndices);
      }
    }
    return out;
  }

 private:
  // assimp's message names its in-memory file "$$$___magic___$$$.EXT"; call it "the file".
  std::string message() const {
    std::string what = importer_.GetErrorString();
    const std::string magic = "$$$___magic___$$$." + format_;
    for (auto at = what.find(magic); at != std::string::npos; at = what.find(magic)) {
      what.replace(at, magic.size(), "the file");
    }
    while (!what.empty() &&
           (what.back() == '.' || std::isspace(static_cast<unsigned char>(what.back())))) {
      what.pop_back();
    }
    return what.empty() ? "assimp could not read it" : what;
  }

  Assimp::Importer importer_;  // assimp logs nothing unless a DefaultLogger is created
  const aiScene* scene_ = nullptr;
  std::string format_;
};

}  // namespace

}  // namespace pp5

extern "C" __attribute__((visibility("default"))) const int pp5_assimp_reader_interface =
    pp5::kAssimpReaderInterface;

extern "C" __attribute__((visibility("default"))) pp5::AssimpReader* pp5_new_assimp_reader() {
  return new pp5::Reader;
}
