// Animation: keyframes, the per-frame scene, Session::set_scene and the GIF encoder.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <map>

#include "sim/animation.hpp"
#include "sim/output/gif.hpp"
#include "sim/scene/scene_loader.hpp"
#include "sim/simulation.hpp"
#include "support.hpp"
#include "tests/gif_reference.hpp"

using namespace pp5;

namespace {

MachineConfig tiny_machine() {
  MachineConfig config = MachineConfig::defaults();
  config.set({"screen.width=128", "screen.height=128", "gp.count=2", "renderer.count=1"});
  return config;
}

AnimationOptions tiny_torus(int frames) {
  AnimationOptions o;
  o.scene.tessellation_u = 24;
  o.scene.tessellation_v = 8;
  o.frames = frames;
  return o;
}

// A scene file's text with `animation` as its "animation".
std::string anim_file(const std::string& animation) {
  return R"({"meshes": [{"builtin": "two-triangles"}, {"builtin": "two-triangles",
             "translate": [3, 0, 0]}],
             "camera": {"eye": [0, 0, 10], "target": [0, 0, 0], "near": 1, "far": 30},
             "animation": )" +
         animation + "}";
}

Animation parse_anim(const std::string& animation, int frames = 0) {
  const std::string text = anim_file(animation);
  SceneParts parts;
  Scene base = parse_scene_json(text, "anim.json", ".", {}, &parts);
  AnimationOptions o;
  o.frames = frames;
  return parse_animation_json(text, "anim.json", std::move(base), parts, o);
}

}  // namespace

TEST_CASE("animation: camera keys interpolate linearly and hold outside the keys", "[animation]") {
  const Animation a = parse_anim(R"({"frames": 5, "fps": 10, "camera": [
      {"frame": 1, "eye": [0, 0, 10], "target": [0, 0, 0]},
      {"frame": 3, "eye": [4, 0, 10], "target": [2, 0, 0], "fov_y_degrees": 60}]})");
  CHECK(a.frames() == 5);
  CHECK(a.fps() == 10);
  CHECK(a.scene(0).camera.eye.x == 0.0f);  // held before the first key
  CHECK(a.scene(2).camera.eye.x == 2.0f);  // halfway
  CHECK(a.scene(2).camera.target.x == 1.0f);
  CHECK(a.scene(2).camera.fov_y_degrees == 50.0f);  // the first key took the file's 40
  CHECK(a.scene(4).camera.eye.x == 4.0f);           // held after the last
}

TEST_CASE("animation: object keys move only their entry, about its centre", "[animation]") {
  const Animation a = parse_anim(R"({"objects": [{"mesh": 1, "keys": [
      {"frame": 0}, {"frame": 4, "translate": [0, 2, 0], "rotate_degrees": [0, 0, 180]}]}]})",
                                 8);
  CHECK(a.frames() == 8);  // --frames wins over the file's
  const Scene s0 = a.scene(0), s2 = a.scene(2), s4 = a.scene(4);
  REQUIRE(s0.mesh.vertices.size() == s4.mesh.vertices.size());
  // The first mesh does not move.
  for (std::size_t i = 0; i < 6; ++i)
    CHECK(s4.mesh.vertices[i].position == s0.mesh.vertices[i].position);
  // The second mesh's centre moves by half the translation at frame 2, all of it at 4, and a
  // half turn about z maps its bounding box onto itself.
  auto centre = [](const Scene& s) {
    glm::dvec3 sum(0);
    for (std::size_t i = 6; i < s.mesh.vertices.size(); ++i)
      sum += glm::dvec3(s.mesh.vertices[i].position);
    return sum / static_cast<double>(s.mesh.vertices.size() - 6);
  };
  CHECK(std::abs(centre(s2).y - centre(s0).y - 1.0) < 1e-5);
  CHECK(std::abs(centre(s4).y - centre(s0).y - 2.0) < 1e-5);
  CHECK(s4.mesh.vertices[6].position != s0.mesh.vertices[6].position);
  CHECK(s0.mesh.triangles == s4.mesh.triangles);
}

TEST_CASE("animation: bad keyframes name the file, the key and what was expected", "[animation]") {
  CHECK_THROWS_WITH(parse_anim(R"({"camera": [{"frame": 2, "eye": [0,0,9], "target": [0,0,0]},
                                   {"frame": 2, "eye": [1,0,9], "target": [0,0,0]}]})"),
                    Catch::Contains("anim.json: key 'animation.camera[1].frame' must be "
                                    "greater than the previous key's frame 2"));
  CHECK_THROWS_WITH(parse_anim(R"({"camera": [{"frame": 0, "eye": [0,0,9]}]})"),
                    Catch::Contains("'animation.camera[0]' needs 'eye' and 'target'"));
  CHECK_THROWS_WITH(parse_anim(R"({"objects": [{"mesh": 2, "keys": [{"frame": 0}]}]})"),
                    Catch::Contains("'animation.objects[0].mesh' must be in [0, 1] (got 2)"));
  CHECK_THROWS_WITH(parse_anim(R"({"spin": 1})"), Catch::Contains("unknown key 'animation.spin'"));
  CHECK_THROWS_WITH(parse_anim(R"({"objects": [{"mesh": 0, "keys": [{"frame": -1}]}]})"),
                    Catch::Contains("'animation.objects[0].keys[0].frame' must be in"));
}

TEST_CASE("animation: the torus turns in 4-space, its primitives stay", "[animation]") {
  const Animation a = load_animation("torus", tiny_torus(4));
  const Scene s0 = a.scene(0), s1 = a.scene(1);
  REQUIRE(s0.mesh.triangles == s1.mesh.triangles);
  CHECK(s0.camera.eye == s1.camera.eye);  // one camera for every frame
  // The projected shape changes: not a rigid motion, so some edge changes length.
  bool stretched = false;
  for (const glm::uvec3& t : s0.mesh.triangles) {
    const float l0 = glm::length(s0.mesh.vertices[t.x].position - s0.mesh.vertices[t.y].position);
    const float l1 = glm::length(s1.mesh.vertices[t.x].position - s1.mesh.vertices[t.y].position);
    stretched = stretched || std::abs(l0 - l1) > 1e-2f * l0;
  }
  CHECK(stretched);
  // A full turn comes back: frame 4 of 4 is frame 0.
  const Scene s4 = a.scene(4);
  for (std::size_t i = 0; i < s0.mesh.vertices.size(); ++i) {
    CHECK(glm::length(s4.mesh.vertices[i].position - s0.mesh.vertices[i].position) < 1e-4f);
  }
}

TEST_CASE("animation: a session's frame k is what a one-frame run of frame k's scene gives",
          "[animation]") {
  const MachineConfig config = tiny_machine();
  const Animation a = load_animation("torus", tiny_torus(3));
  auto program = std::make_shared<const Program>(test::load_program("phong", config));
  // Each frame alone first (SystemC contexts do not nest: one run at a time).
  std::vector<FrameResult> alone;
  for (int k = 0; k < 3; ++k) alone.push_back(simulate_frame(config, a.scene(k), *program, 1));
  // Frames differ: the scene does change.
  CHECK(alone[0].image.flat().rgb != alone[1].image.flat().rgb);
  CHECK(alone[1].image.flat().rgb != alone[2].image.flat().rgb);
  Session session(config, std::make_shared<const Scene>(a.scene(0)), program, 2);
  for (int k = 0; k < 3; ++k) {
    if (k > 0) session.set_scene(std::make_shared<const Scene>(a.scene(k)));
    const FrameResult in_session = session.frame();
    INFO("frame " << k);
    CHECK(in_session.image.flat().rgb == alone[k].image.flat().rgb);
    CHECK(in_session.frame_seconds == alone[k].frame_seconds);
    CHECK(test::without_host(in_session.stats_json) == test::without_host(alone[k].stats_json));
  }
  CHECK(session.summary().frames == 3);
}

TEST_CASE("animation: set_scene refuses a scene with other primitives", "[animation]") {
  const MachineConfig config = tiny_machine();
  auto program = std::make_shared<const Program>(test::load_program("phong", config));
  Session session(config, std::make_shared<const Scene>(make_builtin_scene("two-triangles")),
                  program, 1);
  session.frame();
  session.set_scene(std::make_shared<const Scene>(make_builtin_scene("crossing-quads")));
  CHECK_THROWS_WITH(session.frame(), Catch::Contains("has 4 triangles where the machine's "
                                                     "scene 'two-triangles' has 2"));
}

TEST_CASE("gif: what encode_gif writes decodes to the palette colours of every pixel",
          "[animation]") {
  // Three frames of many colours, so that the code table fills and clears several times.
  std::vector<RgbImage> frames(3);
  std::uint32_t x = 12345;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    RgbImage& i = frames[f];
    i.width = 203;
    i.height = 97 + static_cast<int>(f) * 0;
    i.rgb.resize(static_cast<std::size_t>(i.width) * i.height * 3);
    for (std::size_t p = 0; p < i.rgb.size(); ++p) {
      x = x * 1103515245u + 12345u;
      // Runs of one colour (long strings) and noise (short ones), per frame.
      i.rgb[p] = (p / 600) % 2 == f % 2 ? static_cast<std::uint8_t>(p / 3000 * 40)
                                        : static_cast<std::uint8_t>(x >> 24);
    }
  }
  std::vector<const RgbImage*> list;
  for (const RgbImage& i : frames) list.push_back(&i);
  const std::string bytes = encode_gif(list, 8);
  CHECK(bytes == encode_gif(list, 8));
  const DecodedGif gif = decode_gif(bytes);
  REQUIRE(gif.frames.size() == 3);
  CHECK(gif.width == 203);
  CHECK(gif.height == 97);
  CHECK(gif.delays == std::vector<int>{8, 8, 8});
  for (std::size_t f = 0; f < 3; ++f) {
    std::size_t wrong = 0;
    for (std::size_t p = 0; p < gif.frames[f].size(); ++p) {
      wrong += gif.frames[f][p] != gif_palette_index(&frames[f].rgb[3 * p]);
    }
    CHECK(wrong == 0);
  }
  // A frame at a time (GifWriter, as pp5sim animate encodes; encode_gif is built on it): a
  // frame of another size is refused, naming it, and the frames kept give the same file.
  GifWriter writer(8);
  for (const RgbImage& i : frames) writer.add(i);
  RgbImage other;
  other.width = other.height = 2;
  other.rgb.resize(12);
  CHECK_THROWS_WITH(writer.add(other), "GIF frame 3 is 2x2, frame 0 203x97");
  CHECK(writer.finish() == bytes);
  // A frame buffer's frame, read by rows, gives the bytes of its flat image; a timing-only
  // frame is refused.
  FrameImage framed(203, 97, 128, 64);
  for (int r = 0; r < 4; ++r) {
    const int x0 = (r % 2) * 128, y0 = (r / 2) * 64;
    std::uint8_t* own = framed.own_bytes(x0, y0);
    for (int i = 0; i < 128 * 64 * 3; ++i) own[i] = static_cast<std::uint8_t>(i * 7 + r * 31);
    framed.set_region(x0, y0, framed.own(x0, y0));
  }
  GifWriter by_rows(8), by_flat(8);
  by_rows.add(framed);
  by_flat.add(framed.flat());
  CHECK(by_rows.finish() == by_flat.finish());
  CHECK_THROWS_WITH(by_rows.add(FrameImage(4, 4, 4, 4, false)), "GIF frame 0 holds no pixels");
  // The palette is near: no channel more than half a level away.
  const std::uint8_t c[3] = {200, 13, 128};
  std::uint8_t back[3];
  gif_palette_colour(gif_palette_index(c), back);
  CHECK(std::abs(back[0] - 200) <= 26);
  CHECK(std::abs(back[1] - 13) <= 22);
  CHECK(std::abs(back[2] - 128) <= 26);
}

TEST_CASE("gif: runs of one colour, short and long, across the table's clears, decode exactly",
          "[animation]") {
  // The encoder takes runs of one index without a lookup per pixel (sim/output/gif.cpp): runs
  // of every length from 1 to past what the table holds, at a frame's start and end, between
  // single pixels, of several colours at once (each its own strings), and enough of them that
  // the table fills and is cleared many times over.
  std::uint32_t state = 99;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  const std::uint8_t colours[4][3] = {{0, 0, 0}, {255, 255, 255}, {255, 0, 0}, {0, 102, 255}};
  std::vector<RgbImage> frames;
  for (int f = 0; f < 3; ++f) {
    RgbImage image;
    image.width = 311;
    image.height = 173;
    const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
    std::size_t at = 0;
    while (at < n) {
      const std::uint32_t pick = next();
      const std::size_t length = f == 2          ? 1 + pick % 3
                                 : pick % 7 == 0 ? 1 + pick % 900
                                                 : 1 + pick % 40;
      const std::uint8_t* c = colours[pick >> 20 & 3];
      for (std::size_t k = 0; k < length && at < n; ++k, ++at)
        image.rgb.insert(image.rgb.end(), c, c + 3);
      if (pick % 5 == 0 && at < n) {  // a single pixel of another colour
        const std::uint8_t one[3] = {static_cast<std::uint8_t>(next()),
                                     static_cast<std::uint8_t>(next()), 17};
        image.rgb.insert(image.rgb.end(), one, one + 3);
        ++at;
      }
    }
    frames.push_back(std::move(image));
  }
  std::vector<const RgbImage*> list;
  for (const RgbImage& i : frames) list.push_back(&i);
  const DecodedGif gif = decode_gif(encode_gif(list, 5));
  REQUIRE(gif.frames.size() == frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    std::size_t wrong = 0;
    for (std::size_t p = 0; p < gif.frames[f].size(); ++p)
      wrong += gif.frames[f][p] != gif_palette_index(&frames[f].rgb[3 * p]);
    CAPTURE(f);
    CHECK(wrong == 0);
  }
}

namespace {}  // namespace

TEST_CASE(
    "gif: every byte value of every channel, at every width, gives a textbook encoder's "
    "bytes",
    "[animation]") {
  // The quantiser goes 32 pixels at a time where the host has the instructions, the rest
  // masked; the LZW coder compares runs 64 or 8 bytes at a time. Widths 1 to 70 and around
  // 96 and 128 (every tail length), each channel taking all 256 values (the levels'
  // boundaries among them), runs of one colour of every length up to 300, and frames of
  // region rows of a width that is no multiple of the vector.
  std::uint32_t state = 7;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  std::vector<int> widths;
  for (int w = 1; w <= 70; ++w) widths.push_back(w);
  for (int w : {95, 96, 97, 127, 128, 129, 1280}) widths.push_back(w);
  for (const int w : widths) {
    std::vector<RgbImage> frames(2);
    for (std::size_t f = 0; f < frames.size(); ++f) {
      RgbImage& image = frames[f];
      image.width = w;
      image.height = 512 / w + 3;
      const std::size_t n = static_cast<std::size_t>(w) * image.height;
      for (std::size_t p = 0; p < n;) {
        if (f == 0) {  // every value of each channel in 256 pixels
          const auto v = static_cast<std::uint8_t>(p);
          const std::uint8_t c[3] = {v, static_cast<std::uint8_t>(v * 7 + 3),
                                     static_cast<std::uint8_t>(v * 13 + 5)};
          image.rgb.insert(image.rgb.end(), c, c + 3);
          ++p;
          continue;
        }
        // Runs of one colour, 1 to 300 pixels, and noise.
        const std::uint32_t pick = next();
        const std::size_t length = std::min<std::size_t>(n - p, 1 + pick % 300);
        const std::uint8_t c[3] = {static_cast<std::uint8_t>(pick >> 9 & 1 ? 0 : next()),
                                   static_cast<std::uint8_t>(next()), 0};
        for (std::size_t k = 0; k < length; ++k, ++p) {
          image.rgb.insert(image.rgb.end(), c, c + 3);
          if (pick % 3 == 0) image.rgb.back() = static_cast<std::uint8_t>(next());
        }
      }
    }
    std::vector<const RgbImage*> list{&frames[0], &frames[1]};
    const std::string bytes = encode_gif(list, 3);
    CAPTURE(w);
    CHECK(bytes == gif_textbook(list, 3));
    // The same frames as a frame buffer's region rows, 40 pixels wide.
    if (w > 1) {
      GifWriter by_rows(3);
      for (const RgbImage& image : frames) {
        FrameImage framed(w, image.height, 40, 8);
        for (int y0 = 0; y0 < image.height; y0 += 8) {
          for (int x0 = 0; x0 < w; x0 += 40) {
            std::uint8_t* own = framed.own_bytes(x0, y0);
            for (int y = y0; y < std::min(y0 + 8, image.height); ++y) {
              for (int x = x0; x < std::min(x0 + 40, w); ++x) {
                std::memcpy(own + ((y - y0) * 40 + (x - x0)) * 3,
                            &image.rgb[(static_cast<std::size_t>(y) * w + x) * 3], 3);
              }
            }
            framed.set_region(x0, y0, framed.own(x0, y0));
          }
        }
        by_rows.add(framed);
      }
      CHECK(by_rows.finish() == bytes);
    }
  }
}
