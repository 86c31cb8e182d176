#pragma once
// CSG expressions over a scene's solids (issue 15): the tree a scene file's "csg" gives, and
// its normalisation to a sum of products, the form Goldfeather, Molnar, Turk and Fuchs
// render on Pixel-Planes (each product's surface points classified against its other
// solids by parity).
//
// Contract:
//  - A tree node is a solid (its index in Scene::solids) or an operator over at least two
//    operands: union, intersection, difference (the first operand minus all the others).
//  - normalise_csg gives a sum of products equal to the tree as a point set: De Morgan
//    pushes complements to the solids; a product holding a solid and its complement is
//    dropped (empty), a literal repeated in a product is kept once, a product equal to an
//    earlier one is dropped. Products keep the operands' order.
//  - A product with no positive literal is unbounded (everything outside some solids): it
//    cannot be rendered from the solids' faces, and normalise_csg throws CsgError saying
//    which. More than kMaxCsgProducts products throws CsgError too (the passes grow with
//    them), and so does a node that would expand to more than kMaxCsgIntermediateProducts
//    before simplification, checked before those products are built. Deterministic.
//  - csg_contains(products, inside) evaluates the sum of products given each solid's
//    membership.
#include <stdexcept>
#include <string>
#include <vector>

#include "models/display_list/scene.hpp"

namespace pp5 {

struct CsgError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct CsgNode {
  enum class Op { solid, union_, intersection, difference };
  Op op = Op::solid;
  int solid = -1;
  std::vector<CsgNode> operands;
};

inline constexpr std::size_t kMaxCsgProducts = 64;
// The most products any node may expand to before duplicates and empty products are
// removed; checked before they are built, so that the work is bounded by it and by the
// expression's size.
inline constexpr std::size_t kMaxCsgIntermediateProducts = 4 * kMaxCsgProducts;

// `names` are the solids' names, for messages.
CsgProducts normalise_csg(const CsgNode& tree, const std::vector<std::string>& names);

bool csg_contains(const CsgProducts& products, const std::vector<bool>& inside);

// "a & !b | c": the products for messages and tables.
std::string format_csg(const CsgProducts& products, const std::vector<std::string>& names);

}  // namespace pp5
