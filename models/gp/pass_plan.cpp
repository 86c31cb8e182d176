#include "models/gp/pass_plan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <glm/glm.hpp>
#include <limits>
#include <stdexcept>

namespace pp5 {

namespace {

// Whether the scene has primitives in no solid (the points of point in solid, the plain
// geometry beside a CSG expression).
bool has_unsolid_primitives(const Scene& scene) {
  int in_solids = 0, spheres_in_solids = 0;
  for (const Solid& s : scene.solids) {
    in_solids += s.last - s.first;
    spheres_in_solids += s.last_sphere - s.first_sphere;
  }
  return in_solids < static_cast<int>(scene.mesh.triangles.size()) ||
         spheres_in_solids < static_cast<int>(scene.spheres.size());
}

// A solid with spheres needs the sphere counterpart of the procedure its passes run.
void check_sphere_solids(const Program& program, const Scene& scene, Procedure planned) {
  const Procedure counterpart = planned_procedure(planned, Procedure::sphere);
  if (program.procedure(counterpart).defined) return;
  for (const Solid& s : scene.solids) {
    if (s.last_sphere > s.first_sphere) {
      throw std::runtime_error(fmt::format(
          "program '{}' does not define '{}', which the spheres of solid '{}' of scene '{}' run",
          program.name, kProcedureNames[static_cast<int>(counterpart)], s.name, scene.name));
    }
  }
}

// A solid's bounding box in world space (its triangles' vertices and spheres).
struct PlanBox {
  glm::vec3 lo{std::numeric_limits<float>::max()}, hi{-std::numeric_limits<float>::max()};
  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
};

PlanBox solid_box(const Scene& scene, const Solid& s) {
  PlanBox b;
  const int triangles = static_cast<int>(scene.mesh.triangles.size());
  const int spheres = static_cast<int>(scene.spheres.size());
  for (int t = s.first; t < std::min(s.last, triangles); ++t) {
    for (int k = 0; k < 3; ++k) {
      const auto v = scene.mesh.triangles[static_cast<std::size_t>(t)][k];
      if (v >= scene.mesh.vertices.size()) continue;
      const glm::vec3 p = scene.mesh.vertices[v].position;
      b.lo = glm::min(b.lo, p);
      b.hi = glm::max(b.hi, p);
    }
  }
  for (int i = s.first_sphere; i < std::min(s.last_sphere, spheres); ++i) {
    const Sphere& sp = scene.spheres[static_cast<std::size_t>(i)];
    b.lo = glm::min(b.lo, sp.center - glm::vec3(sp.radius));
    b.hi = glm::max(b.hi, sp.center + glm::vec3(sp.radius));
  }
  // A solid with no geometry in the scene (a plan made before the mesh) bounds nothing.
  if (b.empty())
    b = {glm::vec3(-std::numeric_limits<float>::max()),
         glm::vec3(std::numeric_limits<float>::max())};
  return b;
}

// `layers`: the rounds (surface and classification passes) of each literal of a product of
// two or more literals; 1 for a program that does not peel.
void csg_plan(const Scene& scene, int layers, std::vector<PlannedPass>& plan,
              std::vector<Procedure>& closing) {
  // What the next pass must open with: the folds and merge still owed.
  std::vector<Procedure> owed;
  if (has_unsolid_primitives(scene)) {
    plan.push_back({{Procedure::clear}, PlannedPass::kNoGroup, Procedure::count});
  } else {
    owed.push_back(Procedure::clear);
  }
  for (const std::vector<CsgLiteral>& product : pruned_csg(scene)) {
    // A literal alone is its own result: its nearest surface is the visible one.
    const int rounds = product.size() > 1 ? layers : 1;
    for (const CsgLiteral& literal : product) {
      for (int layer = 0; layer < rounds; ++layer) {
        owed.push_back(layer == 0 ? Procedure::candidate : Procedure::next_layer);
        plan.push_back({owed, literal.solid, Procedure::surface,
                        literal.negated ? PlannedPass::Faces::back : PlannedPass::Faces::front});
        owed.clear();
        for (const CsgLiteral& other : product) {
          if (&other == &literal) continue;
          plan.push_back({owed, other.solid, Procedure::parity, PlannedPass::Faces::all});
          owed = {other.negated ? Procedure::keep_outside : Procedure::keep_inside};
        }
        owed.push_back(Procedure::merge);
      }
    }
  }
  closing = owed;
}

}  // namespace

CsgProducts pruned_csg(const Scene& scene) {
  if (!scene.prune_csg) return scene.csg;
  std::vector<PlanBox> boxes;
  for (const Solid& s : scene.solids) boxes.push_back(solid_box(scene, s));
  CsgProducts out;
  for (const std::vector<CsgLiteral>& product : scene.csg) {
    PlanBox common;
    bool positive = false;
    for (const CsgLiteral& l : product) {
      if (l.negated) continue;
      const PlanBox& b = boxes[static_cast<std::size_t>(l.solid)];
      common = positive ? PlanBox{glm::max(common.lo, b.lo), glm::min(common.hi, b.hi)} : b;
      positive = true;
    }
    if (!positive) {
      out.push_back(product);
      continue;
    }
    if (common.empty()) continue;  // the positive literals share no point
    std::vector<CsgLiteral> kept;
    for (const CsgLiteral& l : product) {
      if (l.negated) {
        const PlanBox& b = boxes[static_cast<std::size_t>(l.solid)];
        const PlanBox meet{glm::max(common.lo, b.lo), glm::min(common.hi, b.hi)};
        if (meet.empty()) continue;  // subtracts nothing from the product
      }
      kept.push_back(l);
    }
    out.push_back(kept);
  }
  return out;
}

int pruned_passes(const Program& program, const Scene& scene) {
  Scene whole = scene;
  whole.prune_csg = false;
  Scene pruned = scene;
  pruned.prune_csg = true;
  return static_cast<int>(make_pass_plan(program, whole).size()) -
         static_cast<int>(make_pass_plan(program, pruned).size());
}

std::vector<PlannedPass> make_pass_plan(const Program& program, const Scene& scene) {
  FrameValues values;
  set_pass_plan(program, scene, values);
  return values.plan;
}

void set_pass_plan(const Program& program, const Scene& scene, FrameValues& values) {
  std::vector<PlannedPass>& plan = values.plan;
  plan.clear();
  values.closing.clear();
  if (program.procedure(Procedure::surface).defined) {
    int layers = 1;
    if (program.procedure(Procedure::next_layer).defined) {
      layers = static_cast<int>(std::max<std::int64_t>(
          1, values.frame.parameters[static_cast<std::size_t>(Parameter::layers)]));
    }
    if (!scene.csg.empty()) {
      check_sphere_solids(program, scene, Procedure::surface);
      check_sphere_solids(program, scene, Procedure::parity);
      csg_plan(scene, layers, plan, values.closing);
    }
    return;
  }
  if (!program.procedure(Procedure::parity).defined) return;
  check_sphere_solids(program, scene, Procedure::parity);
  plan.push_back({{Procedure::clear}, PlannedPass::kNoGroup, Procedure::count});
  for (std::size_t s = 0; s < scene.solids.size(); ++s) {
    plan.push_back({{Procedure::pass}, static_cast<int>(s), Procedure::parity});
  }
}

void check_pass_plan(const Program& program) {
  for (const Procedure own : {Procedure::triangle, Procedure::sphere}) {
    for (const Procedure planned : {Procedure::parity, Procedure::surface}) {
      const Procedure p = planned_procedure(planned, own);
      const ProcedureCode& code = program.procedure(p);
      if (!code.defined) continue;
      const auto extra = code.expressions & ~program.procedure(own).expressions;
      for (int e = 0; e < static_cast<int>(Expression::count); ++e) {
        if (extra.test(static_cast<std::size_t>(e))) {
          throw std::runtime_error(fmt::format(
              "program '{}': procedure '{}' uses expression '{}', which procedure '{}' does "
              "not (a {} pass runs the {}'s packets)",
              program.name, kProcedureNames[static_cast<int>(p)], kExpressions[e].name,
              kProcedureNames[static_cast<int>(own)], kProcedureNames[static_cast<int>(planned)],
              kProcedureNames[static_cast<int>(own)]));
        }
      }
    }
  }
}

}  // namespace pp5
