#include "models/gp/primitive_kind.hpp"

#include "models/gp/sphere.hpp"

namespace pp5 {

namespace {

// The triangle: a face of Scene::mesh. Its geometry is GeometryEngine's (transform and clip
// into a fan of screen triangles, set-up through the expression registry, bounding-box
// binning); its cost is I860Work::triangle.
class TriangleWorker final : public PrimitiveWorker {
 public:
  explicit TriangleWorker(const GeometryEngine& geometry) : geometry_(geometry) {}
  int transform(int index, SetupCounts& counts) override {
    screen_.clear();
    geometry_.transform(index, screen_, counts);
    return static_cast<int>(screen_.size());
  }
  bool setup(int piece, const ExpressionSet& needed, SetupResult& out,
             SetupCounts& counts) override {
    return geometry_.setup(screen_[static_cast<std::size_t>(piece)], needed, out, counts);
  }
  void bin(const SetupResult& result, std::vector<int>& regions) const override {
    geometry_.bin(result, regions);
  }

 private:
  const GeometryEngine& geometry_;
  std::vector<ScreenTriangle> screen_;
};

class TriangleKind final : public PrimitiveKind {
 public:
  const char* name() const override { return "triangle"; }
  Procedure procedure() const override { return Procedure::triangle; }
  int count(const Scene& scene) const override {
    return static_cast<int>(scene.mesh.triangles.size());
  }
  int solid(const Scene& scene, int index) const override { return scene.solid_of_triangle(index); }
  bool supplies(Expression e) const override { return !is_sphere_expression(e); }
  std::unique_ptr<PrimitiveWorker> start(const GeometryEngine& geometry) const override {
    return std::make_unique<TriangleWorker>(geometry);
  }
  OpCounts operations(const GpWorkload& w, const PrimitiveTally& t) const override {
    return I860Work::triangle(w, t.pieces, t.setups, t.regions);
  }
};

}  // namespace

const std::vector<const PrimitiveKind*>& primitive_kinds() {
  static const TriangleKind triangle;
  static const std::vector<const PrimitiveKind*> kinds{&triangle, &sphere_kind()};
  return kinds;
}

DisplayList make_display_list(const Scene& scene) {
  std::vector<int> counts;
  for (const PrimitiveKind* k : primitive_kinds()) counts.push_back(k->count(scene));
  return DisplayList(counts);
}

}  // namespace pp5
