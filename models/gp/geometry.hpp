#pragma once
// The Graphics Processor's per-primitive work, as plain C++: transform, clip, light, and
// compute the fixed-point coefficients of every expression the firmware asks for, then bin
// the result by screen region. The GraphicsProcessor module (graphics_processor.hpp) runs
// this and charges its time; tests use it directly.
//
// Contract:
//  - Vertices are snapped to 1/2^subpixel_bits of a pixel. Edge coefficients are then exact
//    integers, so two triangles sharing an edge give exactly opposite edge functions and
//    every pixel centre on the edge belongs to exactly one of them (the top-left rule).
//  - The GP's arithmetic (significand_bits, gp.significand_bits): below 62 every coefficient
//    of every expression the GP sends is kept to that many significant bits, rounded to
//    nearest, symmetrically about 0 (gp_round, models/gp/expressions.hpp). Each path that
//    forms a coefficient rounds it where it is formed (SetupContext::edge, plane, constant;
//    the side tests; the sphere's quadratics), before any reduction modulo the coefficient
//    width; a test walks the registry to check that every expression's coefficients move.
//    Edge functions stay exactly opposite (parity exact) while the line they describe moves.
//  - Attribute expressions carry fraction_bits fraction bits, are anchored at the first
//    vertex (so rounding error grows with distance from it), and are clamped at the
//    vertices to half a unit inside their range, so that floor() of the value never wraps
//    inside the triangle.
//  - Pixels are sampled at their centres: screen pixel (X, Y) is the point (X + 0.5, Y + 0.5)
//    with Y growing downward; the evaluator is fed integer X, Y.
#include <array>
#include <bitset>
#include <glm/glm.hpp>
#include <mutex>
#include <optional>
#include <vector>

#include "firmware/isa/isa.hpp"
#include "models/display_list/display_list.hpp"
#include "models/display_list/mesh_adjacency.hpp"
#include "models/display_list/scene.hpp"

namespace pp5 {

struct GeometryParams {
  int screen_width = 1280;
  int screen_height = 1024;
  int region_width = 128;
  int region_height = 128;
  int subpixel_bits = 4;
  // The GP's arithmetic: significant bits kept of every coefficient it sends (gp_round); 62 or
  // more keeps every coefficient exact, 24 is IEEE single, 53 IEEE double.
  int significand_bits = 62;
  int depth_bits = 24;
  int fraction_bits = 12;
  int coefficient_bits = 40;
  int result_bits = 40;          // the evaluator's: its sums wrap modulo 2^result_bits
  bool cull_back_faces = false;  // drop triangles facing away from the eye
  // Frame parameters the machine configuration sets (MachineConfig::frame); they win over the
  // scene's Scene::parameters, which win over the declared defaults.
  std::array<std::optional<std::int64_t>, static_cast<int>(Parameter::count)> frame{};
};
// Every field equal (SetupMemo's key). A field added above must be added to it: the
// static_assert in geometry.cpp fails until it is.
bool operator==(const GeometryParams& a, const GeometryParams& b);
inline bool operator!=(const GeometryParams& a, const GeometryParams& b) { return !(a == b); }

// A triangle after projection: screen position (pixels, y down), depth in [0, 1], and the
// attributes the expressions interpolate.
struct ScreenVertex {
  glm::dvec2 position;
  double depth = 0;
  double eye_depth = 0;   // distance along the view axis, eye-space units (clip w)
  glm::dvec3 lit_color;   // 0..1, lit at the vertex
  glm::dvec3 base_color;  // 0..1, unlit material
  glm::dvec3 normal;      // eye space, unit, facing the viewer
  double opacity = 1;     // the material's, 0..1
};
struct ScreenTriangle {
  std::array<ScreenVertex, 3> v;
  glm::dvec3 flat_color;  // lit with the face normal
  int source = 0;         // index of the scene triangle
  bool back = false;      // the scene triangle faces away from the eye (its normals were turned)
};

// Why a triangle produced no packet.
struct SetupCounts {
  std::uint64_t clipped_away = 0;  // wholly outside the view volume
  std::uint64_t degenerate = 0;    // zero area after snapping
  std::uint64_t no_pixels = 0;     // covers no pixel centre
  std::uint64_t overflow = 0;      // a coefficient did not fit evaluator.coefficient_bits
  std::uint64_t clip_splits = 0;   // extra triangles made by clipping
  std::uint64_t culled = 0;        // back-facing, dropped (GeometryParams::cull_back_faces)
  // Accurate scan conversion's side tests (models/gp/accurate_expressions.hpp): triangle edges
  // set up, by how they were classified, in SideKind order (plane, boundary, non_manifold,
  // clipped, degenerate, coplanar). All 0 for a program that sends no side0..2.
  std::array<std::uint64_t, 6> sides{};
  std::uint64_t sphere_near = 0;    // a sphere reaching the near plane (models/gp/sphere.hpp)
  std::uint64_t sphere_behind = 0;  // a sphere wholly behind the eye
  std::uint64_t sphere_far = 0;     // a sphere reaching the far plane
};
// Adds every count (a field added above must be added to it: see geometry.cpp).
SetupCounts& operator+=(SetupCounts& a, const SetupCounts& b);

// The expressions a procedure uses (ProcedureCode::expressions): what the GP computes.
using ExpressionSet = std::bitset<static_cast<int>(Expression::count)>;

struct SetupResult {
  PacketExpressions values;
  int x_min = 0, x_max = -1, y_min = 0, y_max = -1;  // pixel-centre bounding box, inclusive
  bool back = false;  // a triangle facing away from the eye (ScreenTriangle::back)
  // As a new SetupResult, keeping the coefficients' storage.
  void clear() {
    values.expressions.clear();
    x_min = 0;
    x_max = -1;
    y_min = 0;
    y_max = -1;
    back = false;
  }
};

class GeometryEngine {
 public:
  GeometryEngine(const GeometryParams& params, const Scene& scene);

  // Transform, clip and light scene triangle `index`; appends 0 or more screen triangles.
  void transform(int index, std::vector<ScreenTriangle>& out, SetupCounts& counts) const;
  // Coefficients of the expressions in `needed`; false (and counted) if the triangle has no
  // pixels or a coefficient does not fit.
  // The coefficients are computed by the expression registry's entries
  // (models/gp/expressions.hpp) from one SetupContext.
  bool setup(const ScreenTriangle& t, const ExpressionSet& needed, SetupResult& out,
             SetupCounts& counts) const;
  // Regions the bounding box touches, as region indices (row-major).
  void bin(const SetupResult& r, std::vector<int>& regions) const;
  // The frame parameters (a light, reflection coefficients, background), with the direction,
  // half vector, diffuse and specular of the scene's light `light` (0-based). The Renderer
  // binds light 0's to every procedure but `light`, which it runs once per light with that
  // light's.
  std::array<std::int64_t, static_cast<int>(Parameter::count)> frame_parameters(
      int light = 0) const;
  // frame_parameters(0), computed on the first call and kept (all zero for a scene without
  // lights): what set-up reads when an expression folds a frame parameter in.
  const ParameterValues& setup_parameters() const;
  int lights() const { return static_cast<int>(light_eye_.size()); }
  // The frame's and each light's values (expressions zero), from frame_parameters(k).
  FrameValues frame_values() const;

  const GeometryParams& params() const { return params_; }
  const Scene& scene() const { return scene_; }
  // The scene's primitives of every registered kind (models/gp/primitive_kind.hpp).
  const DisplayList& display_list() const { return display_list_; }
  // The scene mesh's face/face adjacency, built on the first call (thread-safe) and kept:
  // only scenes whose program needs an expression that reads it pay for it.
  const MeshAdjacency& adjacency() const;

 private:
  glm::dvec3 light_vertex(const glm::dvec3& color, const glm::dvec3& normal) const;
  // A mesh vertex as every triangle that uses it sees it: eye and clip position, eye-space
  // unit normal, and its colour lit facing the viewer and lit with the normal turned (a
  // back-facing triangle's). Computed once per vertex, on the first transform (thread-safe),
  // with the very operations transform() would do per corner: the same bits.
  struct VertexView {
    glm::dvec3 eye;
    glm::dvec4 clip;
    glm::dvec3 normal;
    glm::dvec3 lit_front, lit_back;
  };
  const std::vector<VertexView>& vertex_views() const;

  GeometryParams params_;
  const Scene& scene_;
  glm::dmat4 view_;
  glm::dmat4 projection_;
  glm::dmat3 normal_matrix_;
  std::vector<glm::dvec3> light_eye_;  // per light
  std::vector<glm::dvec3> half_eye_;
  DisplayList display_list_;
  mutable std::once_flag adjacency_once_;
  mutable std::once_flag setup_parameters_once_;
  mutable ParameterValues setup_parameters_{};
  mutable std::once_flag vertex_views_once_;
  mutable std::vector<VertexView> vertex_views_;
  mutable MeshAdjacency adjacency_;
};

}  // namespace pp5
