#pragma once
// The registry of primitive kinds the display list may hold. A kind supplies what the GP does
// with one of its primitives: transform and clip it into pieces, set each piece up (the
// expressions its procedure uses), bin the result by region, and count the i860 operations;
// and it names the Renderer procedure its packets run. GraphicsProcessor::run walks its share
// of the display list and dispatches every primitive through its kind.
//
// Contract:
//  - primitive_kinds()[k] is kind k: the `kind` of a PrimitiveRef and of a Packet. Kinds are
//    never reordered (the display list's order, and so the split over GPs, follows them).
//  - count(scene): the primitives of the kind in the scene's storage (the triangle kind's
//    storage is scene.mesh.triangles).
//  - start(geometry) makes one GP's worker for the kind; a worker is used by one thread only
//    and keeps its scratch between primitives. transform(index) returns the pieces (0 when
//    the primitive is dropped, counted in `counts`); setup(piece) may be called for each
//    piece of the last transform, in any order.
//  - operations(workload, tally) depends only on the workload (what the procedure asks for)
//    and the tally: the same primitive always costs the same.
//  - Adding a kind changes no result for scenes without primitives of it.
#include <memory>
#include <vector>

#include "firmware/isa/interface.hpp"
#include "models/display_list/display_list.hpp"
#include "models/display_list/scene.hpp"
#include "models/gp/geometry.hpp"
#include "models/gp/i860.hpp"

namespace pp5 {

// What one primitive made: the pieces after clipping, the pieces set up, the region bins its
// packets went to.
struct PrimitiveTally {
  int pieces = 0;
  int setups = 0;
  int regions = 0;
};

class PrimitiveWorker {
 public:
  virtual ~PrimitiveWorker() = default;
  // Transform, clip (and light) primitive `index` of the kind; the pieces that reach set-up.
  virtual int transform(int index, SetupCounts& counts) = 0;
  // The coefficients of `needed` for piece `piece` of the last transform; false (and
  // counted) if it yields no packet.
  virtual bool setup(int piece, const ExpressionSet& needed, SetupResult& out,
                     SetupCounts& counts) = 0;
  // The regions a set-up piece touches (region indices, row-major), appended to `regions`.
  virtual void bin(const SetupResult& result, std::vector<int>& regions) const = 0;
};

class PrimitiveKind {
 public:
  virtual ~PrimitiveKind() = default;
  virtual const char* name() const = 0;
  // The Renderer procedure its packets run; its expressions are what set-up computes.
  virtual Procedure procedure() const = 0;
  virtual int count(const Scene& scene) const = 0;
  // The solid (Scene::solids) primitive `index` of the kind belongs to, -1 for none: the
  // group of its packets, which a pass plan selects by.
  virtual int solid(const Scene& scene, int index) const = 0;
  // Whether its set-up can compute expression e: a procedure of the kind may use only these
  // (the Machine refuses a program that asks for others, naming them).
  virtual bool supplies(Expression e) const = 0;
  virtual std::unique_ptr<PrimitiveWorker> start(const GeometryEngine& geometry) const = 0;
  virtual OpCounts operations(const GpWorkload& workload, const PrimitiveTally& tally) const = 0;
};

const std::vector<const PrimitiveKind*>& primitive_kinds();
inline constexpr int kTriangleKind = 0;
inline constexpr int kSphereKind = 1;
// The sphere kind's registry entry (models/gp/sphere_kind.cpp).
const PrimitiveKind& sphere_kind();

// Every primitive of the scene, kinds in registry order (display_list.hpp).
DisplayList make_display_list(const Scene& scene);

}  // namespace pp5
