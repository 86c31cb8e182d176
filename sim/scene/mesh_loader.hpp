#pragma once
// Mesh files: Wavefront OBJ, PLY (ASCII and binary), STL (ASCII and binary) and OFF, read
// through assimp (the Open Asset Import Library, Debian's libassimp-dev), with our own checks
// on top.
//
// Contract:
//  - Every error is a MeshError whose message starts with "FILE:" (or "FILE:LINE:" where a
//    header check knows the line) and says what was wrong: assimp's own message, or ours,
//    naming the face, corner or vertex (counted from 0) where there is one.
//  - Nothing a file says can make the loader allocate more than the limits allow: the counts
//    OFF, PLY and binary STL headers declare are checked against LoadLimits and against the
//    bytes the file actually holds before assimp sees the bytes; a file whose data ends
//    before the header and face sizes say is refused (assimp would read it as zeros).
//  - Only the named format's importer is used, and it may open no other file. What assimp 5.2
//    mishandles (crashes, leaks, silent clamping; see the guards in mesh_loader.cpp) is
//    checked before it sees the bytes: OFF's face lines, PLY's header and body, ASCII
//    STL's structure, OBJ's indices.
//  - Polygons with more than three vertices are triangulated by our ear clipping in the plane
//    of their Newell normal (not by assimp), so concave polygons come out right.
//  - Coordinates must be finite. Triangles with a repeated vertex or zero area are dropped and
//    counted (they would cover no pixel); edges shared by more than two triangles
//    (non-manifold) are counted and rendered as they are. OBJ points and lines are skipped.
//  - OBJ and STL corners at identical positions become one vertex; PLY and OFF keep the
//    file's vertices. Vertex normals are always recomputed (compute_smooth_normals); vertex
//    colours come from the file where it has them, otherwise from `default_color`.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

#include "sim/scene/scene.hpp"

namespace pp5 {

class MeshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The most triangles a scene may hold, however it is made (mesh files, built-in meshes in a
// scene file, a tessellation): checked before the geometry is built. Measured on the
// development machine at the default screen and machine, a frame costs about 660 bytes and
// 24 us of host time per triangle (a scene of 200 built-in spheres, 793,600 triangles: 526 MB
// and 18.7 s), so the bound is about 1.3 GB and 50 s a frame. A 97 KB scene file of 2,000
// built-in spheres (7.9 M triangles) is refused by it.
inline constexpr std::size_t kMaxSceneTriangles = 2'000'000;

struct LoadLimits {
  std::size_t max_vertices = 4'000'000;
  std::size_t max_triangles = kMaxSceneTriangles;
  std::size_t max_polygon_vertices = 4096;  // per face
};

// What loading found besides the mesh itself.
struct MeshLoadReport {
  std::size_t polygons = 0;            // faces read from the file
  std::size_t triangulated = 0;        // faces with more than three vertices
  std::size_t dropped_degenerate = 0;  // repeated vertex or zero area
  std::size_t non_manifold_edges = 0;  // edges used by more than two triangles
  std::size_t ignored_statements = 0;  // OBJ points, lines and empty faces (0 to 2 vertices)
  std::size_t collapsed_corners = 0;   // faces with a corner repeated at once (1 2 2 3), merged
};

// The formats by file extension (case-insensitive): .obj .ply .stl .off.
bool is_mesh_file(const std::string& path);

// Reads `path`; the format comes from its extension.
Mesh load_mesh(const std::string& path, MeshLoadReport* report = nullptr,
               const LoadLimits& limits = {}, glm::vec3 default_color = glm::vec3(0.8f));

// Parses `data` as `format` ("obj", "ply", "stl" or "off"); `origin` names it in messages.
Mesh parse_mesh(std::string_view data, const std::string& format, const std::string& origin,
                MeshLoadReport* report = nullptr, const LoadLimits& limits = {},
                glm::vec3 default_color = glm::vec3(0.8f));

// Appends the triangles of a simple polygon (indices into `positions`, in order) to `out`,
// by ear clipping in the plane of its Newell normal. Returns false if the polygon is not
// simple (no ear could be found); the remaining part is then fanned so nothing is lost.
bool triangulate_polygon(const std::vector<glm::vec3>& positions,
                         const std::vector<unsigned>& polygon, std::vector<glm::uvec3>& out);

// A scene around one mesh: the camera framed on it from the front and a little above, the
// project's standard light and background.
Scene scene_from_mesh(Mesh mesh, const std::string& name, const std::string& description);

}  // namespace pp5
