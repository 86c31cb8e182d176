// Inputs that must never hang, exhaust memory or be misread (issue 18): non-regular files,
// oversized files, block numbers near 2^63, byte-order marks, programs with tens of
// thousands of fields.
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/checked_number.hpp"
#include "common/escape.hpp"
#include "common/read_file.hpp"
#include "common/strict_json.hpp"
#include "firmware/assembler/assembler.hpp"
#include "sim/scene/mesh_loader.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/simulation.hpp"
#include "support.hpp"

namespace fs = std::filesystem;
using namespace pp5;

namespace {

const std::string kProgram =
    "field z 24\n"
    "field flag 1\n"
    "field red 8\n"
    "field green 8\n"
    "field blue 8\n"
    "output red green blue\n"
    "proc triangle\n"
    "  eall\n";

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// A fresh path in the temporary directory, removed when the test ends.
struct TempPath {
  fs::path path;
  explicit TempPath(const std::string& stem)
      : path(fs::temp_directory_path() /
             (stem + "-" + std::to_string(::getpid()) + "-" +
              std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()))) {}
  ~TempPath() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

}  // namespace

TEST_CASE("only regular files are read, and never more than the cap", "[inputs]") {
  SECTION("a FIFO is refused at once, not waited on") {
    TempPath fifo("pp5-fifo");
    REQUIRE(::mkfifo(fifo.path.c_str(), 0600) == 0);
    CHECK(message_of([&] { read_regular_file(fifo.path, 1000, "a test file"); }) ==
          fifo.path.string() + ": is a FIFO, expected a test file (a regular file)");
    CHECK_THROWS_WITH(assemble_file(fifo.path, {}),
                      Catch::Contains("is a FIFO, expected a firmware program"));
  }
  SECTION("a character device such as /dev/zero is refused, not read forever") {
    CHECK_THROWS_WITH(read_regular_file("/dev/zero", 1000, "a test file"),
                      "/dev/zero: is a character device, expected a test file (a regular file)");
    CHECK_THROWS_WITH(assemble_file("/dev/zero", {}), Catch::Contains("character device"));
  }
  SECTION("a directory") {
    CHECK_THROWS_WITH(assemble_file(fs::temp_directory_path(), {}),
                      Catch::Contains("is a directory, expected a firmware program"));
  }
  SECTION("a missing file names the OS reason") {
    CHECK_THROWS_WITH(read_regular_file("/nonexistent/x.pp5", 10, "a firmware program"),
                      Catch::Contains("No such file or directory"));
  }
  SECTION("a file over the cap is refused before it is read") {
    TempPath big("pp5-big");
    std::ofstream(big.path) << std::string(2000, 'x');
    CHECK_THROWS_WITH(
        read_regular_file(big.path, 1000, "a test file"),
        Catch::Contains("2000 bytes is larger than a test file can be (at most 1000 bytes)"));
    CHECK(read_regular_file(big.path, 2000, "a test file").size() == 2000);
  }
}

TEST_CASE("backing-store block numbers near 2^63 are refused, not wrapped", "[inputs]") {
  CHECK_THROWS_WITH(assemble(kProgram + "  bsst z, 9223372036854775800\nend\n", "big", {}),
                    Catch::Contains("big:9: backing-store blocks 9223372036854775800") &&
                        Catch::Contains("past the end of the store (128 blocks)"));
  CHECK_THROWS_WITH(assemble(kProgram + "  bsld z, 9223372036854775807\nend\n", "big", {}),
                    Catch::Contains("past the end of the store"));
}

TEST_CASE("a block number is not a value that must fit the field", "[inputs]") {
  // bsld into a 1-bit field from block 5: 5 is an address, not a constant for the field.
  const Program p = assemble(kProgram + "  bsld flag, 5\n  bsst flag, 127\nend\n", "ok", {});
  CHECK(p.procedure(Procedure::triangle).code.size() == 3);
  // A constant that does not fit is still refused where it is a value.
  CHECK_THROWS_WITH(assemble(kProgram + "  mov flag, 5\nend\n", "bad", {}),
                    Catch::Contains("constant 5 does not fit the 1-bit destination"));
}

TEST_CASE("a UTF-8 byte-order mark before a program is skipped", "[inputs]") {
  const Program with = assemble("\xEF\xBB\xBF" + kProgram + "end\n", "bom", {});
  const Program without = assemble(kProgram + "end\n", "plain", {});
  CHECK(with.fields.size() == without.fields.size());
  CHECK(with.bits_used() == without.bits_used());
}

TEST_CASE("a program of tens of thousands of fields lays out as a small one does", "[inputs]") {
  // 40,000 one-bit fields, most spilled to a large backing store, each used once. The layout
  // used to recompute every instruction's staging need for every spilled field (quadratic);
  // its time is measured, not asserted here, by bench/bench_assembler.cpp (AssembleWide,
  // which fits the complexity). What is asserted: the same layout rules as for small programs.
  std::string source = "option spill\nfield red 8\nfield green 8\nfield blue 8\n";
  const int n = 40000;
  for (int k = 0; k < n; ++k) source += "field f" + std::to_string(k) + " 1\n";
  source += "output red green blue\nproc triangle\n";
  for (int k = 0; k + 1 < n; k += 2)
    source += "  and f" + std::to_string(k) + ", f" + std::to_string(k + 1) + "\n";
  source += "end\n";
  AssemblerOptions o;
  o.backing_store_bits = 1 << 16;
  o.block_bits = 1;
  const Program p = assemble(source, "wide", o);
  REQUIRE(p.fields.size() == static_cast<std::size_t>(n + 3));
  // Spilling takes fields from the end of the list until the rest and the staging fit: the
  // outputs and the first fields stay, every `and` of two spilled fields stages 2 bits.
  CHECK(p.bits_used() <= o.memory_bits);
  CHECK(p.staging_bits == 2);
  CHECK_FALSE(p.fields[0].spilled);
  const int resident = p.resident_bits - 24;
  CHECK(resident == o.memory_bits - 24 - 2);
  for (int k = 0; k < n; ++k) {
    if (p.fields[static_cast<std::size_t>(k) + 3].spilled != (k >= resident)) {
      FAIL_CHECK("field f" << k
                           << " spilled: " << p.fields[static_cast<std::size_t>(k) + 3].spilled);
      break;
    }
  }
  // Each spilled use is bracketed by a load (two per `and`) and the destination's store.
  const auto& code = p.procedure(Procedure::triangle).code;
  CHECK(code.size() ==
        static_cast<std::size_t>(n / 2) +
            static_cast<std::size_t>(p.procedure(Procedure::triangle).spill_transfers));
}

TEST_CASE("mesh files: what exporters write is read, what cannot be filled is reported",
          "[inputs][mesh]") {
  SECTION("a PLY header line without the 'comment' keyword is a comment") {
    const std::string ply =
        "ply\nformat ascii 1.0\nCreated by SomeExporter 2.1\nelement vertex 3\n"
        "property float x\nproperty float y\nproperty float z\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    MeshLoadReport report;
    const Mesh mesh = parse_mesh(ply, "ply", "exporter.ply", &report);
    CHECK(mesh.triangles.size() == 1);
    // The keywords PLY knows are still checked.
    std::string bad = ply;
    bad.replace(bad.find("element face 1"), 14, "element face x");
    CHECK_THROWS_WITH(parse_mesh(bad, "ply", "bad.ply"),
                      Catch::Contains("element 'face' has count 'x'"));
  }
  SECTION("UTF-16 text is named as such") {
    const std::string utf16le("\xFF\xFEv\0 \0", 6);
    CHECK_THROWS_WITH(parse_mesh(utf16le, "obj", "wide.obj"),
                      "wide.obj: UTF-16 text (it starts with a UTF-16 byte-order mark); save it "
                      "as UTF-8 or ASCII");
    const std::string no_bom("v\0 \0", 4);
    CHECK_THROWS_WITH(parse_mesh(no_bom, "obj", "wide.obj"), Catch::Contains("UTF-16 text"));
  }
  SECTION("a face that visits a vertex again is refused, not stacked") {
    const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 1 2 3 1 2 3 1 2 3\n";
    CHECK_THROWS_WITH(parse_mesh(obj, "obj", "stack.obj"),
                      "stack.obj: face 0 visits vertex 0 4 times (12 corners); a face must be a "
                      "polygon that visits each vertex once");
  }
  SECTION("a corner repeated at once is a collapsed edge, merged") {
    const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2 3 1\n";
    MeshLoadReport report;
    const Mesh mesh = parse_mesh(obj, "obj", "collapsed.obj", &report);
    CHECK(mesh.triangles.size() == 1);
    CHECK(report.collapsed_corners == 1);
    CHECK(report.dropped_degenerate == 0);
  }
  SECTION("an empty face line is counted, not lost") {
    const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf\nf 1 2 3\n";
    MeshLoadReport report;
    const Mesh mesh = parse_mesh(obj, "obj", "empty-f.obj", &report);
    CHECK(mesh.triangles.size() == 1);
    CHECK(report.ignored_statements == 1);
  }
}

TEST_CASE("simulated time past SystemC's 2^64 ps is refused, not wrapped", "[inputs]") {
  // In-range parameters whose frame lasts longer than SystemC can count: a 1 MHz array, a
  // backing store of 100,000 cycles a block of one bit, one Renderer, spilling firmware.
  MachineConfig config = MachineConfig::defaults();
  config.set({"renderer.clock_hz=1e6", "renderer.backing_store_cycles_per_block=100000",
              "renderer.block_bits=1", "renderer.count=1"});
  SceneOptions options;
  options.tessellation_u = 640;
  options.tessellation_v = 128;
  const Scene scene = make_builtin_scene("torus", options);
  const Program program =
      assemble_file(std::string(PP5_SOURCE_DIR) + "/tests/data/firmware/spill_folded_epsilon.pp5",
                    assembler_options(config));
  CHECK_THROWS_WITH(simulate_frame(config, scene, program, 2),
                    Catch::Contains("simulated time ran past what SystemC can count") &&
                        Catch::Contains("renderer0 was busy"));
}

TEST_CASE("a tessellation is refused where it does not apply", "[inputs]") {
  SceneOptions options;
  options.tessellation_u = 8;
  options.tessellation_v = 8;
  CHECK_THROWS_WITH(make_builtin_scene("two-triangles", options),
                    Catch::Contains("scene 'two-triangles' has fixed geometry"));
  CHECK_THROWS_WITH(load_scene(PP5_SOURCE_DIR "/examples/meshes/knot.obj", options),
                    Catch::Contains("is a file, whose geometry is its own"));
  CHECK_NOTHROW(make_builtin_scene("sphere", options));
}

TEST_CASE("untrusted text in messages is escaped and cut short", "[inputs]") {
  CHECK(escape_for_message("plain name.obj") == "plain name.obj");
  CHECK(escape_for_message(std::string("a\0b", 3)) == "a\\x00b");
  CHECK(escape_for_message("x\xff\xfey") == "x\\xff\\xfey");
  CHECK(escape_for_message("line\nnext\t\x1b[31m") == "line\\nnext\\t\\x1b[31m");
  CHECK(escape_for_message("back\\slash") == "back\\\\slash");
  CHECK(escape_for_message("caf\xc3\xa9 \xe2\x80\x94") ==
        "caf\xc3\xa9 \xe2\x80\x94");                               // UTF-8 kept
  CHECK(escape_for_message("\xc0\xaf") == "\\xc0\\xaf");           // an overlong '/' is not UTF-8
  CHECK(escape_for_message("\xed\xa0\x80") == "\\xed\\xa0\\x80");  // a surrogate either
  const std::string huge(1 << 20, 'n');
  const std::string cut = escape_for_message(huge);
  CHECK(cut.size() < 120);
  CHECK_THAT(cut, Catch::EndsWith("... (1048576 bytes)"));
  // A cut never splits a UTF-8 sequence.
  CHECK(escape_for_message("abc\xc3\xa9", 4) == "abc... (5 bytes)");
}

TEST_CASE("numbers are parsed into a checked width, never wrapped", "[inputs]") {
  CHECK(parse_integer<int>("42", "--n") == 42);
  CHECK(parse_integer<int>("-7", "--n") == -7);
  CHECK_THROWS_WITH(parse_integer<int>("4294967301", "--pixel X"),
                    "--pixel X '4294967301': is out of range, expected an integer from "
                    "-2147483648 to 2147483647");
  CHECK_THROWS_WITH(parse_integer<std::uint32_t>("-1", "--n"),
                    Catch::Contains("is out of range, expected an integer from 0 to 4294967295"));
  CHECK_THROWS_WITH(parse_integer<int>("99999999999999999999999", "--n"),
                    Catch::Contains("is out of range"));
  for (const char* bad : {"", " 1", "1 ", "+1", "0x10", "1e3", "1.0", "12abc", "--1"}) {
    CHECK_THROWS_WITH(parse_integer<int>(bad, "--n", 0, 100),
                      Catch::Contains("expected an integer from 0 to 100"));
  }
  CHECK_THROWS_WITH(parse_integer<int>(std::string("1\n\xff"), "--n", 0, 9),
                    "--n '1\\n\\xff': expected an integer from 0 to 9");
  CHECK(json_integer<int>(nlohmann::json(5), "k", 0, 9) == 5);
  CHECK_THROWS_WITH(json_integer<int>(nlohmann::json((std::int64_t{1} << 32) + 5), "k"),
                    "k = 4294967301: is out of range, expected an integer from -2147483648 to "
                    "2147483647");
  CHECK_THROWS_WITH(json_integer<int>(nlohmann::json(std::uint64_t{1} << 63), "k", 0, 9),
                    Catch::Contains("is out of range"));
  CHECK_THROWS_WITH(json_integer<int>(nlohmann::json(2.5), "k", 0, 9),
                    "k = 2.5: expected an integer from 0 to 9");
  CHECK_THROWS_WITH(json_integer<int>(nlohmann::json("3"), "k", 0, 9),
                    "k = \"3\": expected an integer from 0 to 9");
}

TEST_CASE("JSON nesting is bounded before the parser's memory grows with it", "[inputs]") {
  // 200 KB of '[' (and of '{"k":') once took gigabytes: one path string per level.
  const std::string arrays(200'000, '[');
  CHECK_THROWS_WITH(parse_strict_json(arrays, "deep.json"),
                    Catch::Contains("deep.json: containers nested more than 256 deep"));
  std::string objects;
  for (int k = 0; k < 40'000; ++k) objects += "{\"" + std::string(40, 'k') + "\":";
  CHECK_THROWS_WITH(parse_strict_json(objects, "keys.json"),
                    Catch::Contains("nested more than 256 deep"));
  // Up to the limit, documents parse as before.
  const std::string ok = std::string(255, '[') + std::string(255, ']');
  CHECK(parse_strict_json(ok, "ok.json") == nlohmann::json::parse(ok));
  // nlohmann's "[json.exception...]" tag does not reach the user.
  CHECK_THROWS_WITH(
      parse_strict_json("{\"a\": }", "s.json"),
      !Catch::Contains("json.exception") && Catch::StartsWith("s.json: not valid JSON"));
}

TEST_CASE("real mesh files: what the formats allow is read", "[inputs]") {
  const std::string dir = std::string(PP5_SOURCE_DIR) + "/tests/data/meshes/";
  auto area = [](const Mesh& m) {
    double sum = 0;
    for (const glm::uvec3& t : m.triangles) {
      const glm::dvec3 a(m.vertices[t.x].position), b(m.vertices[t.y].position),
          c(m.vertices[t.z].position);
      sum += glm::length(glm::cross(b - a, c - a)) / 2;
    }
    return sum;
  };
  // A UTF-8 byte-order mark before an OBJ: one triangle, not "vertex index 3 out of range".
  const Mesh bom = load_mesh(dir + "bom.obj");
  CHECK(bom.triangles.size() == 1);
  CHECK(bom.vertices.size() == 3);
  // OFF with comments among the vertices and faces: the tetrahedron of tetra.off.
  const Mesh off = load_mesh(dir + "comments.off");
  const Mesh tetra = load_mesh(dir + "tetra.off");
  REQUIRE(off.triangles.size() == 4);
  CHECK(off.vertices.size() == 4);
  CHECK(area(off) == Approx(area(tetra)));
  // A triangle 1e-5 across beside a unit one: kept (assimp's merge collapsed it), the same
  // two triangles as the OFF file gives.
  const Mesh cad = load_mesh(dir + "tiny_cad.obj");
  const Mesh cad_off = load_mesh(dir + "tiny_cad.off");
  CHECK(cad.triangles.size() == 2);
  CHECK(cad_off.triangles.size() == 2);
  CHECK(area(cad) == Approx(area(cad_off)).epsilon(1e-12));
  // A concave ten-corner star: triangulated to exactly its own area (shoelace formula).
  const Mesh star = load_mesh(dir + "star.obj");
  double shoelace = 0;
  for (std::size_t k = 0; k < star.vertices.size(); ++k) {
    const glm::vec3 p = star.vertices[k].position;
    const glm::vec3 q = star.vertices[(k + 1) % star.vertices.size()].position;
    shoelace += (static_cast<double>(p.x) * q.y - static_cast<double>(q.x) * p.y) / 2;
  }
  CHECK(star.triangles.size() == 8);
  CHECK(area(star) == Approx(std::abs(shoelace)).epsilon(1e-6));
}

TEST_CASE("a PLY header of thousands of comment lines is refused before assimp reads it",
          "[inputs]") {
  auto ply = [](int comments) {
    std::string h = "ply\nformat ascii 1.0\n";
    for (int k = 0; k < comments; ++k) h += "comment written by an exporter\n";
    return h +
           "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
           "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  };
  // 20,000 comment lines took assimp 11 s; a few hundred are read as before.
  CHECK(parse_mesh(ply(500), "ply", "c.ply").triangles.size() == 1);
  CHECK_THROWS_WITH(parse_mesh(ply(20'000), "ply", "c.ply"),
                    Catch::Contains("c.ply: the header has more than 1000 lines"));
}
