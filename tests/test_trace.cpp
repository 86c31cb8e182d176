// Per-pixel traces: replay reconstructs pixel memory exactly, windows and filters select
// exactly what they claim, damaged files are rejected with a message, and the exports are
// accepted by real readers.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>

#include "firmware/assembler/assembler.hpp"
#include "models/machine.hpp"
#include "sim/simulation.hpp"
#include "sim/trace/inspect.hpp"
#include "sim/trace/recorder.hpp"
#include "sim/trace/snapshot.hpp"
#include "sim/trace/trace_file.hpp"
#include "tests/support.hpp"

using namespace pp5;
using namespace pp5::test;
namespace fs = std::filesystem;

namespace {

MachineConfig small_config() {
  MachineConfig c = MachineConfig::defaults();
  c.screen.width = 384;
  c.screen.height = 256;
  c.gp.count = 5;
  c.renderer.count = 3;
  return c;
}

const Scene& torus() {
  static const Scene s = make_builtin_scene("torus", {64, 16});
  return s;
}

fs::path temp_dir() {
  const fs::path d = fs::temp_directory_path() /
                     ("pp5_trace_test_" + std::to_string(static_cast<long>(::getpid())));
  fs::create_directories(d);
  return d;
}

// Records `sel` through a frame, writes the trace to a file and reads it back.
trace::Trace record(const MachineConfig& c, const Program& p, const trace::Selection& sel,
                    const std::string& name, int threads = 2, FrameResult* frame = nullptr,
                    const Scene& scene = torus()) {
  trace::Recorder rec(c, scene, p, sel);
  for (int k = 0; k < c.renderer.count; ++k) rec.observer(k);
  FrameResult r = simulate_frame(c, scene, p, threads, [&](int k) { return rec.observer(k); });
  if (frame) *frame = std::move(r);
  const std::string path = (temp_dir() / name).string();
  rec.write(path);
  return trace::read_trace(path);
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A 16 x 16 patch on the torus, inside region 4 of the 3 x 2 regions.
trace::Selection patch() {
  trace::Selection s;
  s.rects.push_back({184, 136, 16, 16});
  return s;
}

}  // namespace

TEST_CASE("replaying a trace reconstructs the selected pixels' memory exactly", "[trace]") {
  const MachineConfig c = small_config();
  const Program p = load_program("phong", c);
  FrameResult frame;
  const trace::Trace t = record(c, p, patch(), "replay.pp5t", 2, &frame);
  // The region's whole pixel memory at its end, as the board's pixel backend holds it.
  const int region = (136 / 128) * c.regions_x() + 184 / 128;
  REQUIRE(region == 4);
  trace::SnapshotTaker taker(c, p, region, std::nullopt);
  simulate_frame(c, torus(), p, 1, [&](int k) { return taker.observer(k); });
  const std::string snap_path = (temp_dir() / "replay.pp5m").string();
  trace::write_snapshot(snap_path, taker.snapshot());
  const trace::Snapshot snap = trace::read_snapshot(snap_path);

  const auto states = trace::replay(t);
  REQUIRE(states.size() == 256);
  int covered = 0, bits_checked = 0;
  for (const auto& [px, state] : states) {
    const int pixel = (px.second % 128) * 128 + px.first % 128;
    REQUIRE(state.value.size() == p.fields.size());  // every field is resident and traced
    for (const auto& [f, value] : state.value) {
      const trace::FieldInfo& fi = t.fields[static_cast<std::size_t>(f)];
      CHECK(value == snap.read(pixel, fi.lo, fi.width));
      bits_checked += fi.width;
    }
    covered += static_cast<int>(state.value.at(t.field_index("covered")));
    // The frame's colour is the replayed output fields.
    const auto i = static_cast<std::size_t>(px.second * frame.image.width() + px.first) * 3;
    CHECK(frame.image.flat().rgb[i] == state.value.at(t.field_index("red")));
    CHECK(frame.image.flat().rgb[i + 1] == state.value.at(t.field_index("green")));
    CHECK(frame.image.flat().rgb[i + 2] == state.value.at(t.field_index("blue")));
  }
  CHECK(bits_checked == 256 * p.resident_bits);
  CHECK(covered > 0);  // the patch is not all background
}

TEST_CASE("traces are identical for any number of host threads and do not change the frame",
          "[trace]") {
  const MachineConfig c = small_config();
  const Program p = load_program("gouraud", c);
  trace::Selection sel;
  sel.rects.push_back({190, 140, 2, 2});
  FrameResult traced;
  record(c, p, sel, "t1.pp5t", 1);
  record(c, p, sel, "t3.pp5t", 3, &traced);
  CHECK(file_bytes((temp_dir() / "t1.pp5t").string()) ==
        file_bytes((temp_dir() / "t3.pp5t").string()));
  const FrameResult plain = simulate_frame(c, torus(), p, 2);
  CHECK(plain.image.flat().rgb == traced.image.flat().rgb);
}

TEST_CASE("windows and filters select exactly what they claim", "[trace]") {
  const MachineConfig c = small_config();
  const Program p = load_program("phong", c);
  trace::Selection base;
  base.rects.push_back({186, 142, 3, 2});
  const trace::Trace full = record(c, p, base, "full.pp5t");
  REQUIRE(full.events.size() > 100);

  SECTION("pixels") {
    std::set<trace::Pixel> seen;
    for (const auto& v : full.values) seen.insert({v.rec.x, v.rec.y});
    const std::set<trace::Pixel> want = {{186, 142}, {187, 142}, {188, 142},
                                         {186, 143}, {187, 143}, {188, 143}};
    CHECK(seen == want);
  }
  SECTION("fields") {
    trace::Selection s = base;
    s.fields = {"z", "covered"};
    const trace::Trace t = record(c, p, s, "fields.pp5t");
    std::set<std::string> names;
    for (const auto& v : t.values) names.insert(t.fields[v.rec.field].name);
    CHECK(names == std::set<std::string>{"z", "covered"});
    // The same instructions, and the same values of those fields, as the full trace.
    CHECK(t.events.size() == full.events.size());
    const auto a = trace::replay(t), b = trace::replay(full);
    for (const auto& [px, st] : a) {
      for (const auto& [f, v] : st.value) CHECK(b.at(px).value.at(f) == v);
    }
  }
  SECTION("micro-instructions") {
    const std::uint64_t first = full.events[full.events.size() / 3].ins.seq;
    const std::uint64_t last = full.events[full.events.size() / 2].ins.seq;
    trace::Selection s = base;
    s.instructions = {static_cast<std::int64_t>(first), static_cast<std::int64_t>(last)};
    const trace::Trace t = record(c, p, s, "window.pp5t");
    std::vector<std::uint64_t> want, got;
    for (const auto& e : full.events) {
      if (e.ins.seq >= first && e.ins.seq < last) want.push_back(e.ins.seq);
    }
    for (const auto& e : t.events) got.push_back(e.ins.seq);
    CHECK(got == want);
    REQUIRE(!t.events.empty());
    CHECK((t.events.front().ins.flags & trace::kFullState));
    // Replaying the window gives the state the full trace had at its end.
    trace::Trace prefix = full;
    std::size_t keep = 0;
    while (keep < prefix.events.size() && prefix.events[keep].ins.seq < last) ++keep;
    const std::size_t values =
        keep < prefix.events.size() ? prefix.events[keep].first_value : prefix.values.size();
    prefix.values.resize(values);
    const auto a = trace::replay(t), b = trace::replay(prefix);
    for (const auto& [px, st] : a) CHECK(st.value == b.at(px).value);
  }
  SECTION("primitives") {
    std::set<int> prims;
    for (const auto& e : full.events) {
      if (e.ins.primitive >= 0) prims.insert(e.ins.primitive);
    }
    REQUIRE(prims.size() >= 3);
    const int lo = *std::next(prims.begin()), hi = *std::prev(prims.end());
    trace::Selection s = base;
    s.primitives = {lo, hi};
    const trace::Trace t = record(c, p, s, "prims.pp5t");
    std::vector<std::uint64_t> want, got;
    for (const auto& e : full.events) {
      if (e.ins.primitive >= lo && e.ins.primitive < hi) want.push_back(e.ins.seq);
    }
    for (const auto& e : t.events) got.push_back(e.ins.seq);
    CHECK(got == want);
  }
  SECTION("frames") {
    trace::Selection s = base;
    s.frames = {1, 5};
    CHECK(record(c, p, s, "frames.pp5t").events.empty());
    s.frames = {0, 1};
    CHECK(record(c, p, s, "frames0.pp5t").events.size() == full.events.size());
  }
}

TEST_CASE("bad selections are rejected with the option's name", "[trace]") {
  const MachineConfig c = small_config();
  const Program p = load_program("phong", c);
  trace::Selection s;
  s.rects.push_back({384, 0, 1, 1});
  CHECK_THROWS_WITH(trace::Recorder(c, torus(), p, s), Catch::Contains("outside the 384 x 256"));
  s.rects = {{0, 0, 1, 1}};
  s.fields = {"zz"};
  CHECK_THROWS_WITH(trace::Recorder(c, torus(), p, s), Catch::Contains("'zz' is not a field"));
  CHECK_THROWS_WITH(trace::parse_range("5:2", "--instructions"), Catch::Contains("empty range"));
  CHECK_THROWS_WITH(trace::parse_rect("1,x", "--pixel"), Catch::Contains("--pixel"));
}

TEST_CASE("truncated and corrupted trace files are rejected with a message", "[trace]") {
  const MachineConfig c = small_config();
  const Program p = load_program("flat", c);
  trace::Selection sel;
  sel.rects.push_back({190, 140, 1, 1});
  record(c, p, sel, "good.pp5t");
  const std::string good = file_bytes((temp_dir() / "good.pp5t").string());
  REQUIRE_NOTHROW(trace::parse_trace(good, "good.pp5t"));

  // Prefixes are rejected, and name the file: every length in the preamble, around the end
  // of the header, and a spread through the records.
  const std::size_t header_end =
      trace::kPreambleBytes + (static_cast<unsigned char>(good[12]) |
                               static_cast<unsigned char>(good[13]) << 8 |
                               static_cast<unsigned char>(good[14]) << 16);
  std::set<std::size_t> cuts;
  for (std::size_t n = 0; n < 40; ++n) cuts.insert(n);
  for (std::size_t n = header_end - 2; n < header_end + 20; ++n) cuts.insert(n);
  for (std::size_t n = header_end; n < good.size(); n += good.size() / 50 + 1) cuts.insert(n);
  for (std::size_t n = good.size() - 9; n < good.size(); ++n) cuts.insert(n);
  for (const std::size_t n : cuts) {
    INFO("prefix of " << n << " bytes");
    CHECK_THROWS_WITH(trace::parse_trace(good.substr(0, n), "cut.pp5t"),
                      Catch::StartsWith("cut.pp5t: "));
  }
  CHECK_THROWS_WITH(trace::parse_trace(good.substr(0, good.size() - 3), "cut.pp5t"),
                    Catch::Contains("truncated at byte"));
  // Any flipped byte after the magic is caught (by the version, the lengths or the checksum).
  for (std::size_t at = 8; at < good.size(); at += good.size() / 40 + 1) {
    std::string bad = good;
    bad[at] = static_cast<char>(bad[at] ^ 0x5a);
    INFO("byte " << at);
    CHECK_THROWS_AS(trace::parse_trace(bad, "bad.pp5t"), trace::TraceError);
  }
  std::string flipped = good;
  flipped[good.size() - 20] ^= 1;
  CHECK_THROWS_WITH(trace::parse_trace(flipped, "bad.pp5t"), Catch::Contains("checksum mismatch"));
  CHECK_THROWS_WITH(trace::parse_trace("GIF89a..........", "x.gif"),
                    Catch::Contains("not a pp5sim trace"));
  std::string version = good;
  version[8] = 9;
  CHECK_THROWS_WITH(trace::parse_trace(version, "v.pp5t"), Catch::Contains("version 9"));

  // A header with a valid checksum but an impossible field map (issue 18).
  const trace::Trace t = trace::parse_trace(good, "good.pp5t");
  {
    nlohmann::json h = t.header;
    h["firmware"]["fields"][0]["lo"] = 5000;
    CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(h, {}, 0), "f.pp5t"),
                      Catch::Contains("field 'z' lo = 5000: is out of range, expected an integer "
                                      "from -1 to"));
    h = t.header;
    h["firmware"]["fields"][0]["lo"] = 200;
    h["firmware"]["fields"][0]["width"] = 60;
    CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(h, {}, 0), "f.pp5t"),
                      Catch::Contains("outside the") && Catch::Contains("bits of pixel memory"));
    h = t.header;
    h["firmware"]["fields"][0]["width"] = 65;
    CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(h, {}, 0), "f.pp5t"),
                      Catch::Contains("width = 65: is out of range, expected an integer from 1 "
                                      "to 64"));
    h = t.header;
    h["firmware"]["memory_bits"] = 1 << 30;
    CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(h, {}, 0), "f.pp5t"),
                      Catch::Contains("firmware.memory_bits = 1073741824: is out of range, "
                                      "expected an integer from 1 to 1024"));
    // Numbers that an int would wrap into a valid one (2^32 + 190 -> 190) are refused.
    h = t.header;
    h["pixels"][0][0] = (std::int64_t{1} << 32) + 190;
    CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(h, {}, 0), "f.pp5t"),
                      Catch::Contains("pixel x = 4294967486: is out of range"));
    h = t.header;
    h["firmware"]["memory_bits"] = (std::int64_t{1} << 32) + 208;
    CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(h, {}, 0), "f.pp5t"),
                      Catch::Contains("memory_bits = 4294967504: is out of range"));
    h = t.header;
    h["firmware"]["fields"][0]["width"] = 24.5;
    CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(h, {}, 0), "f.pp5t"),
                      Catch::Contains("width = 24.5: expected an integer from 1 to 64"));
  }
  // Every header value a report reads is checked when the trace is read, not where a report
  // happens to use it: the VCD's clock (a clock of 0 divided by zero), the scene and firmware
  // names and instruction texts shown (control bytes, a megabyte), the opcodes, the outputs.
  {
    auto refused = [&](const std::function<void(nlohmann::json&)>& forge) {
      nlohmann::json h = t.header;
      forge(h);
      try {
        trace::parse_trace(trace::encode_trace(h, {}, 0), "f.pp5t");
      } catch (const trace::TraceError& e) {
        return std::string(e.what());
      }
      return std::string("accepted");
    };
    for (const double hz : {0.0, -5.0, 1e300, 1e-300}) {
      CHECK_THAT(refused([&](nlohmann::json& h) { h["config"]["renderer"]["clock_hz"] = hz; }),
                 Catch::Contains("config.renderer.clock_hz") &&
                     Catch::Contains("expected a number from 1e6 to 1e9"));
    }
    CHECK_THAT(refused([](nlohmann::json& h) { h["config"]["renderer"]["clock_hz"] = "x"; }),
               Catch::Contains("config.renderer.clock_hz = \"x\""));
    CHECK_THAT(refused([](nlohmann::json& h) { h.erase("scene"); }),
               Catch::Contains("key 'scene' not found") && !Catch::Contains("json.exception"));
    CHECK_THAT(refused([](nlohmann::json& h) { h["scene"]["name"] = "\x1b[2J"; }),
               Catch::Contains("scene.name = \"\\\\u001b[2J\": expected text"));
    CHECK_THAT(refused([](nlohmann::json& h) { h["scene"]["name"] = std::string(100000, 'x'); }),
               Catch::Contains("(100002 bytes)") && Catch::Contains("at most 256 bytes"));
    CHECK_THAT(refused([](nlohmann::json& h) { h["firmware"]["name"] = 5; }),
               Catch::Contains("firmware.name = 5: expected text"));
    CHECK_THAT(refused([](nlohmann::json& h) { h["firmware"]["outputs"][0] = 1; }),
               Catch::Contains("an output field's name = 1"));
    CHECK_THAT(refused([](nlohmann::json& h) { h["firmware"]["fields"][0]["name"] = "a\nb"; }),
               Catch::Contains("a field's name"));
    CHECK_THAT(
        refused(
            [](nlohmann::json& h) { h["firmware"]["procedures"]["triangle"][0]["opcode"] = 256; }),
        Catch::Contains("instruction 0 of procedure triangle: opcode = 256: is out of range"));
    CHECK_THAT(refused([](nlohmann::json& h) {
                 h["firmware"]["procedures"]["triangle"][0]["text"] = std::string(5000, 'y');
               }),
               Catch::Contains("instruction 0 of procedure triangle: text") &&
                   Catch::Contains("at most 1000 bytes"));
    // The checked values are the ones the reports use.
    CHECK(t.clock_hz == t.header["config"]["renderer"]["clock_hz"].get<double>());
    CHECK(t.scene_name == t.header["scene"]["name"].get<std::string>());
    CHECK(t.procedures[1][0].opcode ==
          t.header["firmware"]["procedures"]["triangle"][0]["opcode"].get<int>());
  }

  // Records with a valid checksum but impossible contents.
  std::vector<std::uint8_t> recs;
  trace::append(recs, trace::ValueRecord{0, 1, 1, 5});
  CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(t.header, recs, 1), "v.pp5t"),
                    Catch::Contains("value record before any instruction record"));
  recs.clear();
  trace::InstructionRecord ins;
  ins.index = 999;
  trace::append(recs, ins);
  CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(t.header, recs, 1), "i.pp5t"),
                    Catch::Contains("not in the header's firmware"));
  recs.clear();
  trace::append(recs, trace::InstructionRecord{});
  trace::append(recs, trace::ValueRecord{999, 1, 1, 5});
  CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(t.header, recs, 2), "f.pp5t"),
                    Catch::Contains("not a traced field"));
  recs.clear();
  trace::append(recs, trace::InstructionRecord{});
  trace::append(recs, trace::ValueRecord{0, 190, 140, 5});
  REQUIRE_NOTHROW(trace::parse_trace(trace::encode_trace(t.header, recs, 2), "ok.pp5t"));
  CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(t.header, recs, 3), "n.pp5t"),
                    Catch::Contains("past the record section"));
  CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(t.header, recs, 1), "m.pp5t"),
                    Catch::Contains("bytes left after the 1 records"));
  recs.clear();
  trace::append(recs, trace::InstructionRecord{});
  trace::append(recs, trace::ValueRecord{0, 2, 1, 5});
  CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(t.header, recs, 2), "p.pp5t"),
                    Catch::Contains("pixel 2,1, which the header does not list"));
  recs[0] = 7;
  CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace(t.header, recs, 2), "k.pp5t"),
                    Catch::Contains("unknown record kind 7"));
  CHECK_THROWS_WITH(trace::parse_trace(trace::encode_trace({{"x", 1}}, {}, 0), "h.pp5t"),
                    Catch::Contains("bad header"));
}

TEST_CASE("why names the last writer - diff finds where two programs diverge", "[trace]") {
  const MachineConfig c = small_config();
  trace::Selection sel;
  sel.rects.push_back({190, 140, 1, 1});
  const trace::Trace phong = record(c, load_program("phong", c), sel, "phong.pp5t");
  const trace::Trace gouraud = record(c, load_program("gouraud", c), sel, "gouraud.pp5t");
  const auto st = trace::replay(phong).at({190, 140});
  REQUIRE(st.value.at(phong.field_index("covered")) == 1);
  const std::string why = trace::why_report(phong, {190, 140});
  CHECK_THAT(why, Catch::Contains("red        = ") && Catch::Contains("mov red, term[7:0]"));
  CHECK_THAT(why, Catch::Contains("qload z, depth"));
  // The writer of z is a triangle packet whose z value matches what was recorded after it.
  const auto& e = phong.events[st.last_writer.at(phong.field_index("z"))];
  CHECK(e.ins.primitive >= 0);
  CHECK(phong.text(e.ins).text == "qload z, depth");

  bool diverged = false;
  const std::string d = trace::diff_report(phong, gouraud, std::nullopt, diverged);
  CHECK(diverged);
  CHECK_THAT(d, Catch::Contains("first divergence after packet") && Catch::Contains("triangle"));
  trace::diff_report(phong, phong, std::nullopt, diverged);
  CHECK_FALSE(diverged);
  CHECK_THAT(trace::bitmap_report(phong), Catch::Contains("[23:0]"));
}

TEST_CASE("traces show each light's procedure, between the triangles and shade", "[trace]") {
  const MachineConfig c = small_config();
  Scene lit = torus();
  lit.lights.push_back({glm::normalize(glm::vec3(1, -0.3f, 0.5f)), 0.5f, 0.4f, 16.0f});
  trace::Selection sel;
  sel.rects.push_back({190, 140, 1, 1});
  FrameResult frame;
  const trace::Trace t = record(c, load_program("phong", c), sel, "lights.pp5t", 2, &frame, lit);
  std::vector<int> lights;
  std::uint64_t last_triangle = 0, first_light = ~0ull, last_light = 0, first_shade = ~0ull;
  for (const trace::Event& e : t.events) {
    const auto proc = static_cast<Procedure>(e.ins.procedure);
    if (proc == Procedure::triangle) last_triangle = std::max(last_triangle, e.ins.seq);
    if (proc == Procedure::shade) first_shade = std::min(first_shade, e.ins.seq);
    if (proc != Procedure::light) continue;
    CHECK(e.ins.primitive == -1);
    if (lights.empty() || lights.back() != e.ins.light) lights.push_back(e.ins.light);
    first_light = std::min(first_light, e.ins.seq);
    last_light = std::max(last_light, e.ins.seq);
    CHECK(trace::packet_label(e.ins) == "light " + std::to_string(e.ins.light));
  }
  CHECK(lights == std::vector<int>{0, 1});
  CHECK(last_triangle < first_light);
  CHECK(last_light < first_shade);
  // `why` names the light that last wrote the level.
  const std::string why = trace::why_report(t, {190, 140});
  CHECK_THAT(why, Catch::Contains("level") && Catch::Contains("light 1"));
}

TEST_CASE("the VCD export is accepted by GTKWave's vcd2fst", "[trace]") {
  const MachineConfig c = small_config();
  trace::Selection sel;
  sel.rects.push_back({190, 140, 2, 1});
  const trace::Trace t = record(c, load_program("phong", c), sel, "vcd.pp5t");
  const std::string v = trace::vcd(t);
  CHECK_THAT(v, Catch::Contains("$scope module pixel_190_140 $end"));
  CHECK_THAT(v, Catch::Contains("enabled_pixels"));
  const fs::path vcd = temp_dir() / "t.vcd", fst = temp_dir() / "t.fst";
  write_file_atomically(vcd.string(), v);
  if (std::system("command -v vcd2fst > /dev/null 2>&1") != 0) {
    WARN("vcd2fst (package gtkwave) is not installed: the VCD was not checked by a reader");
    return;
  }
  const std::string cmd = "vcd2fst " + vcd.string() + " " + fst.string() + " > /dev/null 2>&1";
  CHECK(std::system(cmd.c_str()) == 0);
  CHECK(fs::file_size(fst) > 0);
}

TEST_CASE("snapshots: a region's memory at a chosen point, files and images", "[trace]") {
  const MachineConfig c = small_config();
  const Program p = load_program("phong", c);
  trace::Selection sel;
  sel.rects.push_back({190, 140, 1, 1});
  const trace::Trace t = record(c, p, sel, "snap.pp5t");
  // After the instruction that last wrote z, the snapshot holds that value.
  const auto st = trace::replay(t).at({190, 140});
  const auto& e = t.events[st.last_writer.at(t.field_index("z"))];
  trace::SnapshotTaker taker(c, p, static_cast<int>(e.ins.region), e.ins.seq);
  simulate_frame(c, torus(), p, 2, [&](int k) { return taker.observer(k); });
  const trace::Snapshot& s = taker.snapshot();
  const int pixel = (140 % 128) * 128 + 190 % 128;
  const auto& z = t.fields[static_cast<std::size_t>(t.field_index("z"))];
  CHECK(s.read(pixel, z.lo, z.width) == st.value.at(t.field_index("z")));

  const RgbImage mask = trace::field_image(s, "covered");
  std::set<int> levels(mask.rgb.begin(), mask.rgb.end());
  CHECK(levels == std::set<int>{0, 255});
  const RgbImage depth = trace::field_image(s, "z");
  CHECK(depth.width == 128);
  CHECK_THROWS_WITH(trace::field_image(s, "nope"), Catch::Contains("no such field"));

  const std::string path = (temp_dir() / "s.pp5m").string();
  trace::write_snapshot(path, s);
  std::string bytes = file_bytes(path);
  write_file_atomically(path, bytes.substr(0, bytes.size() / 2));
  CHECK_THROWS_WITH(trace::read_snapshot(path), Catch::Contains("truncated"));
  bytes[bytes.size() / 2] ^= 4;
  write_file_atomically(path, bytes);
  CHECK_THROWS_WITH(trace::read_snapshot(path), Catch::Contains("checksum mismatch"));

  // Forged headers, checksum recomputed (issue 18): the reader checks their meaning.
  auto forged = [&](const std::function<void(nlohmann::json&)>& edit) {
    trace::Snapshot f = s;
    edit(f.header);
    trace::write_snapshot(path, f);
    return path;
  };
  CHECK_THROWS_WITH(trace::read_snapshot(
                        forged([](nlohmann::json& h) { h["firmware"]["fields"][0]["lo"] = 200; })),
                    Catch::Contains("lo = 200: is out of range"));
  CHECK_THROWS_WITH(trace::read_snapshot(forged([](nlohmann::json& h) {
                      h["firmware"]["fields"][0]["lo"] = 150;
                      h["firmware"]["fields"][0]["width"] = 24;
                    })),
                    Catch::Contains("outside the") && Catch::Contains("bits of pixel memory"));
  CHECK_THROWS_WITH(
      trace::read_snapshot(
          forged([](nlohmann::json& h) { h["firmware"]["fields"][0]["width"] = 1000; })),
      Catch::Contains("width = 1000: is out of range, expected an integer from 1 to 64"));
  CHECK_THROWS_WITH(trace::read_snapshot(forged(
                        [](nlohmann::json& h) { h["firmware"]["fields"][0]["lo"] = "low"; })),
                    Catch::Contains("lo = \"low\": expected an integer"));
  CHECK_THROWS_WITH(trace::read_snapshot(forged([](nlohmann::json& h) { h["width"] = 1 << 30; })),
                    Catch::Contains("width = 1073741824: is out of range, expected an integer "
                                    "from 64 to 1024"));
  CHECK_THROWS_WITH(trace::read_snapshot(forged([](nlohmann::json& h) { h["memory_bits"] = -3; })),
                    Catch::Contains("memory_bits = -3: is out of range"));
  // 2^32 + 128 would be 128 as an int: refused, not read as a 128-pixel-wide region.
  CHECK_THROWS_WITH(trace::read_snapshot(forged(
                        [](nlohmann::json& h) { h["width"] = (std::int64_t{1} << 32) + 128; })),
                    Catch::Contains("width = 4294967424: is out of range"));
  CHECK_NOTHROW(trace::read_snapshot(forged([](nlohmann::json&) {})));

  trace::SnapshotTaker never(c, p, static_cast<int>(e.ins.region), 999999999);
  simulate_frame(c, torus(), p, 2, [&](int k) { return never.observer(k); });
  CHECK_THROWS_WITH(never.snapshot(), Catch::Contains("choose one of those"));
}

TEST_CASE("programs that spill: resident fields are traced, spilled ones refused", "[trace]") {
  MachineConfig c = small_config();
  const Program p = assemble_file(std::string(PP5_SOURCE_DIR) + "/tests/data/firmware/spill.pp5",
                                  assembler_options(c));
  std::string spilled, resident;
  for (const FieldDecl& f : p.fields) (f.spilled ? spilled : resident) = f.name;
  REQUIRE(!spilled.empty());
  trace::Selection sel;
  sel.rects.push_back({190, 140, 1, 1});
  sel.fields = {spilled};
  CHECK_THROWS_WITH(trace::Recorder(c, torus(), p, sel), Catch::Contains("backing store"));
  sel.fields.clear();
  FrameResult frame;
  const trace::Trace t = record(c, p, sel, "spill.pp5t", 2, &frame);
  const auto st = trace::replay(t).at({190, 140});
  const auto i = static_cast<std::size_t>(140 * frame.image.width() + 190) * 3;
  CHECK(frame.image.flat().rgb[i] == st.value.at(t.field_index("red")));
  CHECK(frame.image.flat().rgb[i + 2] == st.value.at(t.field_index("blue")));
  CHECK_THAT(trace::bitmap_report(t), Catch::Contains("spilled to the backing store"));
}
