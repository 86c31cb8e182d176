#include "models/gp/pass_plan.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace pp5 {

std::vector<PlannedPass> make_pass_plan(const Program& program, const Scene& scene) {
  std::vector<PlannedPass> plan;
  if (!program.procedure(Procedure::parity).defined) return plan;
  plan.push_back({Procedure::clear, PlannedPass::kNoGroup, Procedure::count});
  for (std::size_t s = 0; s < scene.solids.size(); ++s) {
    plan.push_back({Procedure::pass, static_cast<int>(s), Procedure::parity});
  }
  return plan;
}

void check_pass_plan(const Program& program) {
  const ProcedureCode& parity = program.procedure(Procedure::parity);
  if (!parity.defined) return;
  const auto extra = parity.expressions & ~program.procedure(Procedure::triangle).expressions;
  for (int e = 0; e < static_cast<int>(Expression::count); ++e) {
    if (extra.test(static_cast<std::size_t>(e))) {
      throw std::runtime_error(
          fmt::format("program '{}': procedure 'parity' uses expression '{}', which procedure "
                      "'triangle' does not (a parity pass runs the triangle's packets)",
                      program.name, kExpressions[e].name));
    }
  }
}

}  // namespace pp5
