// The built-in scene "folded-slab": made to provoke the depth errors of edge round-off that
// accurate scan conversion removes (sim/analysis/scan_conversion.hpp).
#include "sim/scene/builtin_folded_slab.hpp"

#include <glm/glm.hpp>
#include <utility>

namespace pp5 {

Scene make_folded_slab() {
  // A closed slab 2 wide and 1.2 high. Its front is folded into kFolds ridges whose faces stand
  // at about 80 degrees to the screen (grazing the view, so their depth changes fast across
  // the screen); its flat back lies kGap behind the valleys. A pixel centre in a valley
  // that snapping hands to the wrong face gets that steep face's plane carried past the
  // valley, deeper than the back, which then shows through. The front and back are grids of
  // kRows rows, and four walls close the slab, so every edge has two triangles and every ray
  // crosses the surface an even number of times.
  constexpr int kFolds = 12;
  constexpr int kColumns = 2 * kFolds + 1;
  constexpr int kRows = 16;
  constexpr float kRidge = 0.5f;
  constexpr float kGap = 0.02f;
  const glm::vec3 front_colour(0.85f, 0.75f, 0.55f);
  const glm::vec3 back_colour(0.15f, 0.35f, 0.95f);
  Mesh mesh;
  auto index = [](int side, int i, int j) {
    return static_cast<unsigned>(side * kColumns * (kRows + 1) + j * kColumns + i);
  };
  for (int side = 0; side < 2; ++side) {
    for (int j = 0; j <= kRows; ++j) {
      for (int i = 0; i < kColumns; ++i) {
        const float x = -1.0f + 2.0f * static_cast<float>(i) / static_cast<float>(kColumns - 1);
        const float y = -0.6f + 1.2f * static_cast<float>(j) / static_cast<float>(kRows);
        const float z = side == 0 ? (i % 2 == 1 ? kRidge : 0.0f) : -kGap;
        mesh.vertices.push_back({{x, y, z},
                                 {0.0f, 0.0f, side == 0 ? 1.0f : -1.0f},
                                 side == 0 ? front_colour : back_colour});
      }
    }
  }
  // Counter-clockwise seen from outside: the front from +z, the back from -z; each wall from
  // its own side. quad(a, b, c, d) is counter-clockwise from outside.
  auto quad = [&](unsigned a, unsigned b, unsigned c, unsigned d) {
    mesh.triangles.emplace_back(a, b, c);
    mesh.triangles.emplace_back(a, c, d);
  };
  for (int j = 0; j < kRows; ++j) {
    for (int i = 0; i + 1 < kColumns; ++i) {
      quad(index(0, i, j), index(0, i + 1, j), index(0, i + 1, j + 1), index(0, i, j + 1));
      quad(index(1, i, j), index(1, i, j + 1), index(1, i + 1, j + 1), index(1, i + 1, j));
    }
  }
  for (int i = 0; i + 1 < kColumns; ++i) {
    quad(index(0, i, 0), index(1, i, 0), index(1, i + 1, 0), index(0, i + 1, 0));  // bottom
    quad(index(0, i, kRows), index(0, i + 1, kRows), index(1, i + 1, kRows),
         index(1, i, kRows));  // top
  }
  for (int j = 0; j < kRows; ++j) {
    quad(index(0, 0, j), index(0, 0, j + 1), index(1, 0, j + 1), index(1, 0, j));  // left
    quad(index(0, kColumns - 1, j), index(1, kColumns - 1, j), index(1, kColumns - 1, j + 1),
         index(0, kColumns - 1, j + 1));  // right
  }
  compute_smooth_normals(mesh);
  Scene scene;
  scene.name = "folded-slab";
  scene.description =
      "A closed slab whose front is folded into steep ridges just in front of its back face: "
      "edge round-off lets the back show through (accurate scan conversion)";
  scene.mesh = std::move(mesh);
  scene.camera = frame_mesh(scene.mesh, glm::vec3(0.1f, 0.2f, 1.0f), 40.0f, 1.05f);
  scene.lights = {default_light(scene.camera)};
  scene.background = glm::vec3(0.05f, 0.05f, 0.08f);
  return scene;
}

}  // namespace pp5
