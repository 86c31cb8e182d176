// Mesh and scene files: every good file loads as what it describes, every bad one ends in a
// message that names the file, the line or element and what was expected.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "firmware/assembler/assembler.hpp"
#include "fuzz/fuzz_targets.hpp"
#include "models/machine.hpp"
#include "sim/scene/mesh_loader.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/simulation.hpp"

using namespace pp5;

namespace {

std::string data_path(const std::string& rel) {
  return std::string(PP5_SOURCE_DIR) + "/tests/data/" + rel;
}

double area(const Mesh& m) {
  double sum = 0;
  for (const auto& t : m.triangles) {
    const glm::dvec3 a(m.vertices[t.x].position), b(m.vertices[t.y].position),
        c(m.vertices[t.z].position);
    sum += 0.5 * glm::length(glm::cross(b - a, c - a));
  }
  return sum;
}

// The message of whatever `f` throws, or "" if it does not throw.
template <typename F>
std::string error_of(F f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("every mesh format loads the same tetrahedron", "[loaders]") {
  for (const char* name : {"tetra.off", "tetra_color.off", "tetra.stl", "tetra_binary.stl",
                           "tetra_ascii.ply", "tetra_binary.ply", "tetra_big_endian.ply"}) {
    INFO(name);
    MeshLoadReport report;
    const Mesh m = load_mesh(data_path(std::string("meshes/") + name), &report);
    CHECK(m.vertices.size() == 4);
    REQUIRE(m.triangles.size() == 4);
    CHECK(report.polygons == 4);
    CHECK(report.non_manifold_edges == 0);
    CHECK(area(m) == Approx(1.5 + std::sqrt(3.0) / 2));
    // Outward winding is kept: every face normal points away from the centroid.
    const glm::vec3 centre(0.25f);
    for (const auto& t : m.triangles) {
      const glm::vec3 a = m.vertices[t.x].position, b = m.vertices[t.y].position,
                      c = m.vertices[t.z].position;
      CHECK(glm::dot(glm::cross(b - a, c - a), (a + b + c) / 3.0f - centre) > 0);
    }
  }
  const Mesh colored = load_mesh(data_path("meshes/tetra_ascii.ply"));
  CHECK(colored.vertices[0].color == glm::vec3(1, 0, 0));
  const Mesh coff = load_mesh(data_path("meshes/tetra_color.off"));
  CHECK(coff.vertices[2].color == glm::vec3(0, 0, 1));
}

TEST_CASE("quads and concave polygons are triangulated exactly", "[loaders]") {
  MeshLoadReport report;
  const Mesh cube = load_mesh(data_path("meshes/cube.obj"), &report);
  CHECK(cube.triangles.size() == 12);
  CHECK(report.triangulated == 6);
  CHECK(area(cube) == Approx(24.0));

  const Mesh l_shape = load_mesh(data_path("meshes/concave.obj"), &report);
  REQUIRE(l_shape.triangles.size() == 4);
  // A fan from the first corner would cover the notch (area 4 with overlap); ear clipping
  // covers exactly the L's area of 3 with every triangle facing +z like the polygon.
  CHECK(area(l_shape) == Approx(3.0));
  for (const auto& t : l_shape.triangles) {
    const glm::vec3 a = l_shape.vertices[t.x].position, b = l_shape.vertices[t.y].position,
                    c = l_shape.vertices[t.z].position;
    CHECK(glm::cross(b - a, c - a).z > 0);
  }
}

TEST_CASE("a self-intersecting polygon is fanned and reported as not simple", "[loaders]") {
  const std::vector<glm::vec3> bowtie = {{0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {0, 1, 0}};
  std::vector<glm::uvec3> out;
  triangulate_polygon(bowtie, {0, 1, 2, 3}, out);
  CHECK(out.size() == 2);
}

TEST_CASE("zero-area triangles are dropped and counted - non-manifold edges render", "[loaders]") {
  MeshLoadReport report;
  const Mesh m = load_mesh(data_path("meshes/zero_area.obj"), &report);
  CHECK(m.triangles.size() == 1);
  CHECK(report.dropped_degenerate == 2);
  const Mesh book = load_mesh(data_path("meshes/nonmanifold.obj"), &report);
  CHECK(book.triangles.size() == 3);
  CHECK(report.non_manifold_edges == 1);
}

TEST_CASE("every bad mesh or scene file gets its own message", "[loaders]") {
  const std::pair<const char*, const char*> cases[] = {
      {"bad/empty.obj", "empty.obj: empty file"},
      {"bad/malformed.obj", "malformed.obj:3: expected 'v' to be followed by numbers, got 'zero'"},
      {"bad/nan.obj", "nan.obj: face 0, corner 2: z is NaN, expected a finite number"},
      {"bad/inf.obj", "inf.obj: face 0, corner 2: z is infinite, expected a finite number"},
      {"bad/bad_index.obj",
       "bad_index.obj:4: vertex index 7 out of range (the file has 3 'v' lines)"},
      {"bad/two_corners.obj",
       "two_corners.obj: no faces found, expected at least one triangle (faces of 1 or 2 vertices, "
       "points or lines, skipped: 1)"},
      {"bad/no_faces.obj", "no_faces.obj: no faces found, expected at least one triangle"},
      {"bad/truncated.off", "truncated.off:2: declares 4 vertices and 4 faces"},
      {"bad/absurd_count.off", "declares 1000000000000 vertices; the limit is 4000000"},
      {"bad/absurd_count.stl", "declares 4000000000 triangles"},
      {"bad/truncated.stl", "need 284 bytes, but the file has 264"},
      {"bad/nan_binary.stl",
       "nan_binary.stl: face 0, corner 0: x is NaN, expected a finite number"},
      {"bad/truncated_ascii.stl", "truncated_ascii.stl:5: unexpected end of file, expected z"},
      {"bad/inf.ply", "inf.ply: vertex 2: z is infinite, expected a finite number"},
      {"bad/truncated_header.ply", "no 'end_header' line"},
      {"bad/truncated_binary.ply",
       "truncated_binary.ply: element 'face' declares 4 items, more than the 45 bytes of data can "
       "hold (truncated file?)"},
      // assimp reads a text file that ends early as zeros and a binary one as whatever
      // follows; the loader checks OFF's lines and walks a PLY body first.
      {"bad/truncated_ascii.ply",
       "truncated_ascii.ply:21: unexpected end of file in face 3 (truncated file?)"},
      {"bad/truncated_face.off", "truncated_face.off:11: face 3: expected 3 vertex indices"},
      {"bad/truncated_quad.ply",
       "truncated_quad.ply: the data ends in face 0, at byte 218 of 233 (truncated file?)"},
      // assimp would reserve what a list's count says: 2^31 indices took it 16 GB.
      {"bad/huge_list.ply",
       "huge_list.ply: face 0: a list of 2147483647 entries; the limit is 4096"},
      {"bad/wrong_type.json", "key 'meshes[0].scale' must be a number (got string)"},
      {"bad/unknown_key.json", "unknown key 'meshes[0].colour'"},
      {"bad/no_meshes.json", "missing key 'meshes'"},
      {"bad/out_of_range.json", "key 'light.ambient' must be in [0, 1] (got 2)"},
      {"bad/bad_index.json", "key 'meshes[0].triangles[0][2]' is 3, outside [0, 3)"},
      {"bad/syntax.json", "syntax.json: not valid JSON"},
      {"bad/missing_mesh.json", "missing.obj: cannot open the file"},
      {"bad/bad_mesh.json", "nan.obj: face 0, corner 2: z is NaN, expected a finite number"},
      {"bad/path_name.json", "key 'name' must be a plain name"},
  };
  for (const auto& [file, message] : cases) {
    INFO(file);
    const std::string path = data_path(file);  // C++17 lambdas cannot capture a binding
    const std::string what = error_of([&] { load_scene(path); });
    CHECK_THAT(what, Catch::Contains(message));
  }
  CHECK_THAT(error_of([] { load_scene("nope"); }), Catch::Contains("unknown scene 'nope'"));
}

TEST_CASE("limits bound what a file can make the loader allocate", "[loaders]") {
  LoadLimits tiny;
  tiny.max_vertices = 3;
  CHECK_THAT(error_of([&] { load_mesh(data_path("meshes/tetra.off"), nullptr, tiny); }),
             Catch::Contains("declares 4 vertices; the limit is 3"));
  CHECK_THAT(error_of([&] { load_mesh(data_path("meshes/cube.obj"), nullptr, tiny); }),
             Catch::Contains("cube.obj: 8 vertices; the limit is 3"));
  // A PLY that declares more faces than its bytes could hold is refused before reading.
  const std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float "
      "y\nproperty float z\nelement face 1500000\nproperty list uchar int vertex_indices\n"
      "end_header\n" +
      std::string(36, '\0');
  CHECK_THAT(error_of([&] { parse_mesh(ply, "ply", "mem.ply"); }),
             Catch::Contains("element 'face' declares 1500000 items"));
}

TEST_CASE("a PLY header declares its format and each element once", "[loaders]") {
  // assimp 5.2 frees memory it never allocated when an element is declared twice (found by
  // fuzzing: fuzz/regressions/mesh/ply-second-vertex-element-leak).
  const std::string vertex =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string body = "end_header\n0 0 0\n1 0 0\n0 1 0\n";
  CHECK_THAT(error_of([&] {
               parse_mesh("ply\nformat ascii 1.0\n" + vertex + vertex + body, "ply", "two.ply");
             }),
             Catch::Contains("two.ply:7: a second element 'vertex' (the first is line 3)"));
  CHECK_THAT(error_of([&] {
               parse_mesh("ply\nformat ascii 1.0\nformat binary_big_endian 1.0\n" + vertex + body,
                          "ply", "f.ply");
             }),
             Catch::Contains("f.ply:3: a second 'format' line (the first is line 2)"));
}

TEST_CASE("scene files combine meshes, transforms, materials, camera and light", "[loaders]") {
  const Scene s = load_scene(data_path("scenes/two_meshes.json"));
  CHECK(s.name == "two-meshes");
  const Mesh sphere = make_builtin_scene("sphere").mesh;
  REQUIRE(s.mesh.triangles.size() == 12 + sphere.triangles.size());
  CHECK(s.mesh.vertices.front().color == glm::vec3(0.9f, 0.3f, 0.2f));
  CHECK(s.mesh.vertices.back().color == glm::vec3(0.2f, 0.5f, 0.9f));
  CHECK(s.ambient == Approx(0.2));
  REQUIRE(s.lights.size() == 1);
  CHECK(glm::length(s.lights[0].direction) == Approx(1.0));
  CHECK(s.background == glm::vec3(0.1f, 0.1f, 0.12f));
  // The sphere was scaled by 0.8 and moved to x = 2.5.
  const BoundingSphere b =
      bounding_sphere(Mesh{{s.mesh.vertices.begin() + 8, s.mesh.vertices.end()}, {}});
  CHECK(b.center.x == Approx(2.5).margin(1e-4));
  CHECK(b.radius == Approx(0.8 * bounding_sphere(sphere).radius).epsilon(1e-4));

  const Scene inl = load_scene(data_path("scenes/inline.json"));
  CHECK(inl.mesh.triangles.size() == 1);
  CHECK(inl.camera.near_plane == 1.0f);
}

TEST_CASE("a mesh file renders through the firmware", "[loaders]") {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=128", "screen.height=128", "renderer.count=1", "gp.count=1"});
  const Scene scene = load_scene(data_path("meshes/cube.obj"));
  const Program program = assemble_file(std::string(PP5_SOURCE_DIR) + "/firmware/programs/flat.pp5",
                                        assembler_options(config));
  const FrameResult r = simulate_frame(config, scene, program, 1);
  const glm::ivec3 bg = glm::ivec3(glm::round(scene.background * 255.0f));
  int covered = 0;
  for (int p = 0; p < 128 * 128; ++p) {
    const glm::ivec3 c(r.image.flat().rgb[3 * p], r.image.flat().rgb[3 * p + 1],
                       r.image.flat().rgb[3 * p + 2]);
    covered += c != bg;
  }
  // The framed cube fills a good part of the frame.
  CHECK(covered > 128 * 128 / 5);
}

TEST_CASE("the fuzz corpus and every kept crasher run cleanly through the fuzz targets",
          "[loaders][fuzz]") {
  namespace fs = std::filesystem;
  const std::pair<const char*, void (*)(const std::uint8_t*, std::size_t)> targets[] = {
      {"mesh", fuzz::mesh},         {"scene", fuzz::scene}, {"config", fuzz::config},
      {"asm", fuzz::assembler},     {"trace", fuzz::trace}, {"snapshot", fuzz::snapshot},
      {"molecule", fuzz::molecule}, {"csg", fuzz::csg}};
  int inputs = 0;
  for (const auto& [name, run] : targets) {
    for (const char* set : {"corpus", "regressions"}) {
      const fs::path dir = fs::path(PP5_SOURCE_DIR) / "fuzz" / set / name;
      if (!fs::exists(dir)) continue;
      for (const auto& entry : fs::directory_iterator(dir)) {
        if (!entry.is_regular_file() || entry.path().filename() == "README.md") continue;
        INFO(entry.path().string());
        std::ifstream in(entry.path(), std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(in)), {});
        REQUIRE_NOTHROW(run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
        ++inputs;
      }
    }
  }
  CHECK(inputs > 40);
}

TEST_CASE("numbers beyond double's range are errors that name the file or key", "[loaders]") {
  // Found by fuzz_config and fuzz_scene: nlohmann::json reports them as out_of_range, not as
  // a parse error, and they used to escape the parsers' handlers.
  CHECK_THAT(
      error_of([] { MachineConfig::from_file(data_path("bad/config_number_overflow.json")); }),
      Catch::Contains("config_number_overflow.json: not valid JSON"));
  MachineConfig c = MachineConfig::defaults();
  CHECK_THAT(error_of([&] { c.set("gp.count=1e999"); }),
             Catch::Contains("value '1e999' of key 'gp.count' is not a number"));
  CHECK_THAT(error_of([] { parse_scene_json(R"({"meshes": 1e999})", "s.json", "."); }),
             Catch::Contains("s.json: not valid JSON"));
}
