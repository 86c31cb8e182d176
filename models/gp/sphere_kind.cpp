// The sphere primitive kind (models/gp/sphere.hpp): one piece per sphere (two for a sphere of
// a solid: its near and far hemispheres) or none, set up
// through the expression registry's sphere_* entries, binned by the ellipse's bounding box.
#include <array>

#include "models/gp/expressions.hpp"
#include "models/gp/primitive_kind.hpp"
#include "models/gp/sphere.hpp"

namespace pp5 {

namespace {

class SphereWorker final : public PrimitiveWorker {
 public:
  explicit SphereWorker(const GeometryEngine& geometry)
      : geometry_(geometry), projector_(geometry.params(), geometry.scene().camera) {}
  // A sphere of a solid is two pieces, its near and its far hemisphere (a front and a back
  // face to a pass plan); any other sphere one, its near hemisphere.
  int transform(int index, SetupCounts& counts) override {
    const Scene& scene = geometry_.scene();
    const Sphere& s = scene.spheres[static_cast<std::size_t>(index)];
    if (!projector_.project(s, index, screen_[0], counts)) return 0;
    if (scene.solid_of_sphere(index) < 0) return 1;
    SetupCounts unused;  // the same sphere: dropped by both or neither
    return projector_.project(s, index, screen_[1], unused, true) ? 2 : 1;
  }
  bool setup(int piece, const ExpressionSet& needed, SetupResult& out,
             SetupCounts& counts) override {
    static const ScreenTriangle kNoTriangle{};
    const GeometryParams& p = geometry_.params();
    const ScreenSphere& screen = screen_[static_cast<std::size_t>(piece)];
    SetupContext c{p, geometry_.scene().camera, kNoTriangle};
    c.sphere = &screen;
    out.back = screen.far;
    c.f_scale = std::ldexp(1.0, p.fraction_bits);
    c.depth_max = std::ldexp(1.0, p.depth_bits) - 1.0;
    out.x_min = screen.x_min;
    out.x_max = screen.x_max;
    out.y_min = screen.y_min;
    out.y_max = screen.y_max;
    for (const ExpressionEntry& e : expression_registry()) {
      const int k = static_cast<int>(e.id);
      // Only its own: a caller may pass every procedure's expressions.
      if (!needed.test(k) || !is_sphere_expression(e.id)) continue;
      if (!e.compute(c, out.values.expressions[static_cast<std::size_t>(k)])) {
        ++counts.overflow;
        return false;
      }
    }
    return true;
  }
  void bin(const SetupResult& result, std::vector<int>& regions) const override {
    geometry_.bin(result, regions);
  }

 private:
  const GeometryEngine& geometry_;
  SphereProjector projector_;
  std::array<ScreenSphere, 2> screen_;
};

class SphereKind final : public PrimitiveKind {
 public:
  const char* name() const override { return "sphere"; }
  Procedure procedure() const override { return Procedure::sphere; }
  int count(const Scene& scene) const override { return static_cast<int>(scene.spheres.size()); }
  int solid(const Scene& scene, int index) const override { return scene.solid_of_sphere(index); }
  bool supplies(Expression e) const override { return is_sphere_expression(e); }
  std::unique_ptr<PrimitiveWorker> start(const GeometryEngine& geometry) const override {
    return std::make_unique<SphereWorker>(geometry);
  }
  OpCounts operations(const GpWorkload& w, const PrimitiveTally& t) const override {
    return sphere_operations(w, t.setups, t.regions);
  }
};

}  // namespace

const PrimitiveKind& sphere_kind() {
  static const SphereKind kind;
  return kind;
}

}  // namespace pp5
