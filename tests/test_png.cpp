#include <stdlib.h>

#include <catch2/catch.hpp>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/frame_encoder.hpp"
#include "sim/image/png_writer.hpp"
#include "sim/output/gif.hpp"

namespace fs = std::filesystem;
using pp5::read_png;
using pp5::RgbImage;
using pp5::write_png;

namespace {

// A fresh directory under the system temp directory, removed with everything in it at scope exit.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "pp5_png_test_XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

RgbImage pattern_image(int width, int height) {
  RgbImage image;
  image.width = width;
  image.height = height;
  image.rgb.resize(static_cast<std::size_t>(width) * height * 3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < 3; ++c) {
        image.rgb[(static_cast<std::size_t>(y) * width + x) * 3 + c] =
            static_cast<std::uint8_t>((x * 37 + y * 11 + c * 101 + x * y) & 0xff);
      }
    }
  }
  return image;
}

}  // namespace

TEST_CASE("write_png and read_png round-trip the exact bytes", "[png]") {
  TempDir dir;
  // Sizes from one pixel to a row of 100,000 pixels.
  for (auto [w, h] : {std::pair{1, 1}, std::pair{7, 5}, std::pair{64, 3}, std::pair{3, 64},
                      std::pair{1000, 300}, std::pair{100000, 3}}) {
    CAPTURE(w, h);
    const RgbImage image = pattern_image(w, h);
    const std::string path = dir.file("pattern.png");
    write_png(path, image);
    const RgbImage back = read_png(path);
    CHECK(back.width == w);
    CHECK(back.height == h);
    CHECK(back.rgb == image.rgb);
    CHECK_FALSE(fs::exists(path + ".tmp"));
  }
}

TEST_CASE("the encoder's runs and literals decode to the exact bytes", "[png]") {
  // What the writer's deflate stream is made of (sim/image/png_writer.cpp): runs of a byte
  // (distance 1) of every length from 1 to past the longest match (258), runs of a pixel
  // (distance 3), rows like the one above (all 0 after the Up filter), noise (literals only,
  // every byte value), a uniform image (one length symbol dominating, a skewed code) and a
  // tall one whose Adler-32 sums many reductions.
  TempDir dir;
  auto make = [](int w, int h, auto pixel) {
    RgbImage image;
    image.width = w;
    image.height = h;
    image.rgb.resize(static_cast<std::size_t>(w) * h * 3);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        for (int c = 0; c < 3; ++c)
          image.rgb[(static_cast<std::size_t>(y) * w + x) * 3 + c] = pixel(x, y, c);
      }
    }
    return image;
  };
  std::uint32_t state = 12345;
  auto noise = [&state](int, int, int) {
    state = state * 1664525u + 1013904223u;
    return static_cast<std::uint8_t>(state >> 24);
  };
  // Noise with short repeats of the byte before or the pixel before (runs of 2 to 5 bytes,
  // so that runs start just before, at and just after the ends of the encoder's 16-byte
  // blocks), in the order make() asks for the bytes.
  std::vector<std::uint8_t> made;
  auto repeats = [&state, &made](int, int, int) {
    state = state * 1664525u + 1013904223u;
    const unsigned pick = state >> 28;
    std::uint8_t b = static_cast<std::uint8_t>(state >> 20);
    if (pick < 5 && !made.empty()) b = made.back();
    if (pick >= 5 && pick < 9 && made.size() >= 3) b = made[made.size() - 3];
    made.push_back(b);
    return b;
  };
  const std::vector<RgbImage> images = {
      make(1, 1, noise),
      make(2, 1, [](int, int, int) { return std::uint8_t{7}; }),
      make(1, 3, [](int, int, int) { return std::uint8_t{9}; }),
      make(61, 37, repeats),
      make(300, 40,
           [](int x, int y, int c) {  // runs whose lengths grow along the row
             return static_cast<std::uint8_t>(((x * 3 + c) / (1 + y * 7)) * 53);
           }),
      make(200, 30,
           [](int x, int y, int c) {  // flat colours changing from row to row
             return static_cast<std::uint8_t>((x / 17) * 40 + y * 9 + c * 70);
           }),
      make(257, 19, noise),
      make(500, 500, [](int, int, int) { return std::uint8_t{200}; }),
      make(3, 20000, [](int x, int y, int c) {
        return static_cast<std::uint8_t>(y % 5 == 0 ? 255 : (x + y / 3 + c) & 0xff);
      })};
  // The files' bytes, pinned (FNV-1a 64 of each): the encoder's speed-ups must not change
  // one byte of what it writes (a deliberate change of the stream updates these).
  const std::uint64_t pinned[] = {
      0xc6e3b3f45d8a9077ull, 0x1ed332f9fb469544ull, 0xbaf6a64b3f471f55ull,
      0x91ea75d3f8606922ull, 0x37f8adece706e425ull, 0x23052630c75dc6f2ull,
      0xa0fc59b0e1dfb9a1ull, 0xbd241913fb582786ull, 0x52b5f0a39484994bull};
  REQUIRE(images.size() == std::size(pinned));
  for (std::size_t k = 0; k < images.size(); ++k) {
    const std::string bytes = pp5::encode_png(images[k]);
    std::uint64_t hash = 14695981039346656037ull;
    for (const char c : bytes) hash = (hash ^ static_cast<std::uint8_t>(c)) * 1099511628211ull;
    CAPTURE(k);
    CHECK(hash == pinned[k]);
  }
  for (const RgbImage& image : images) {
    CAPTURE(image.width, image.height);
    const std::string path = dir.file("runs.png");
    write_png(path, image);
    const RgbImage back = read_png(path);
    CHECK(back.width == image.width);
    CHECK(back.height == image.height);
    CHECK(back.rgb == image.rgb);
  }
}

TEST_CASE("write_png replaces an existing file", "[png]") {
  TempDir dir;
  const std::string path = dir.file("out.png");
  write_png(path, pattern_image(4, 4));
  const RgbImage second = pattern_image(9, 2);
  write_png(path, second);
  CHECK(read_png(path).rgb == second.rgb);
  CHECK_FALSE(fs::exists(path + ".tmp"));
}

TEST_CASE("write_png into a missing directory throws and leaves no file", "[png]") {
  TempDir dir;
  const std::string path = dir.file("no/such/dir/out.png");
  REQUIRE_THROWS_AS(write_png(path, pattern_image(3, 3)), std::runtime_error);
  REQUIRE_THROWS_WITH(write_png(path, pattern_image(3, 3)), Catch::Contains(path));
  CHECK_FALSE(fs::exists(path));
  CHECK_FALSE(fs::exists(path + ".tmp"));
  CHECK(fs::is_empty(dir.path()));
}

TEST_CASE("write_png rejects inconsistent images without touching the file system", "[png]") {
  TempDir dir;
  const std::string path = dir.file("bad.png");
  RgbImage short_buffer = pattern_image(4, 4);
  short_buffer.rgb.pop_back();
  CHECK_THROWS_WITH(write_png(path, short_buffer), Catch::Contains(path));
  RgbImage empty;
  CHECK_THROWS_AS(write_png(path, empty), std::runtime_error);
  RgbImage negative;
  negative.width = -2;
  negative.height = 3;
  CHECK_THROWS_AS(write_png(path, negative), std::runtime_error);
  CHECK(fs::is_empty(dir.path()));
}

TEST_CASE("read_png names the path when the file is missing or not a PNG", "[png]") {
  TempDir dir;
  const std::string missing = dir.file("missing.png");
  CHECK_THROWS_WITH(read_png(missing), Catch::Contains(missing));
  const std::string text = dir.file("text.png");
  std::ofstream(text) << "this is not a PNG file\n";
  CHECK_THROWS_AS(read_png(text), std::runtime_error);
  CHECK_THROWS_WITH(read_png(text), Catch::Contains(text));
}

namespace {
// A frame of 2 x 2 regions of 4 x 3 pixels, its bytes a pattern that `seed` changes.
FrameImage encoder_frame(int seed) {
  FrameImage frame(8, 6, 4, 3);
  for (int y0 = 0; y0 < 6; y0 += 3) {
    for (int x0 = 0; x0 < 8; x0 += 4) {
      std::uint8_t* b = frame.own_bytes(x0, y0);
      for (int i = 0; i < 4 * 3 * 3; ++i)
        b[i] = static_cast<std::uint8_t>(seed * 37 + x0 + y0 * 5 + i * 11);
      frame.set_region(x0, y0, frame.own(x0, y0));
    }
  }
  return frame;
}
}  // namespace

TEST_CASE("FrameEncoder gives, in frame order, the bytes the encoders give on the calling thread",
          "[png]") {
  GifWriter gif(5);
  std::vector<std::string> pngs;
  std::string gif_bytes;
  for (int k = 0; k < 7; ++k) {
    const FrameImage frame = encoder_frame(k);
    pngs.push_back(encode_png(frame));
    gif.add(frame);
  }
  gif_bytes = gif.finish();
  for (int waiting : {0, 2, 10}) {
    std::vector<int> order;
    std::string got_gif;
    int added = 0;
    bool finishing = false;
    FrameEncoder encoder(
        5,
        [&](EncodedFrame& e) {
          order.push_back(e.frame);
          REQUIRE(e.frame < static_cast<int>(pngs.size()));
          CHECK(e.png == pngs[static_cast<std::size_t>(e.frame)]);
          got_gif += e.gif;
          // Sunk from add() only once more than `waiting` frames are queued behind it.
          if (!finishing) CHECK(added - e.frame > waiting);
        },
        static_cast<std::size_t>(waiting));
    for (int k = 0; k < 7; ++k) {
      ++added;
      encoder.add(k, encoder_frame(k));
    }
    CHECK(static_cast<int>(order.size()) == std::max(0, 7 - waiting));
    finishing = true;
    got_gif += encoder.finish();
    CHECK(order == std::vector<int>{0, 1, 2, 3, 4, 5, 6});
    CHECK(got_gif == gif_bytes);
  }
}

TEST_CASE("FrameEncoder: an encoding error reaches the caller, and no frame after it is sunk",
          "[png]") {
  std::vector<int> order;
  FrameEncoder encoder(
      5, [&](EncodedFrame& e) { order.push_back(e.frame); }, 1);
  encoder.add(0, encoder_frame(0));
  encoder.add(1, FrameImage(8, 6, 4, 3, false));  // a timing-only frame: no pixels to encode
  CHECK_THROWS_WITH(encoder.add(2, encoder_frame(2)), Catch::Contains("holds no pixels"));
  CHECK(order == std::vector<int>{0});
}
