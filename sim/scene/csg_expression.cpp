#include "sim/scene/csg_expression.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>
#include <utility>

namespace pp5 {

namespace {

// The sum of products of `node`, complemented when `negate`.
CsgProducts sum_of_products(const CsgNode& node, bool negate) {
  using Op = CsgNode::Op;
  if (node.op == Op::solid) return {{CsgLiteral{node.solid, negate}}};
  // difference(a, b...) = a & !b & ...; each operator becomes a union or an intersection of
  // (possibly complemented) operands, De Morgan swapping the two under a complement.
  std::vector<std::pair<const CsgNode*, bool>> terms;
  for (std::size_t k = 0; k < node.operands.size(); ++k) {
    const bool complement = node.op == Op::difference && k > 0;
    terms.push_back({&node.operands[k], complement != negate});
  }
  const bool is_union = (node.op == Op::union_) != negate;
  // Every bound is checked before the products it limits are built: a union's count is the
  // sum of its operands', an intersection's the product, so a small expression (an
  // intersection of unions) cannot expand to millions of products first.
  const std::size_t bound = kMaxCsgIntermediateProducts;
  CsgProducts out;
  if (is_union) {
    // A product already in the union adds nothing: dropped as it comes, so that a union of
    // many equal operands stays as small as its distinct products.
    auto key = [](const std::vector<CsgLiteral>& product) {
      std::vector<std::pair<int, bool>> k;
      k.reserve(product.size());
      for (const CsgLiteral& l : product) k.emplace_back(l.solid, l.negated);
      return k;
    };
    std::set<std::vector<std::pair<int, bool>>> seen;
    for (const auto& [n, c] : terms) {
      CsgProducts p = sum_of_products(*n, c);
      p.erase(std::remove_if(
                  p.begin(), p.end(),
                  [&](const std::vector<CsgLiteral>& q) { return !seen.insert(key(q)).second; }),
              p.end());
      if (p.size() > bound - out.size()) {
        throw CsgError(
            fmt::format("the expression expands to more than {} products (before "
                        "duplicates are removed); at most {} can be drawn",
                        bound, kMaxCsgProducts));
      }
      out.insert(out.end(), p.begin(), p.end());
    }
    return out;
  }
  out = {{}};
  for (const auto& [n, c] : terms) {
    const CsgProducts p = sum_of_products(*n, c);
    if (!p.empty() && out.size() > bound / p.size()) {
      throw CsgError(
          fmt::format("the expression expands to more than {} products (before "
                      "duplicates are removed); at most {} can be drawn",
                      bound, kMaxCsgProducts));
    }
    CsgProducts next;
    for (const auto& a : out) {
      for (const auto& b : p) {
        std::vector<CsgLiteral> product = a;
        product.insert(product.end(), b.begin(), b.end());
        next.push_back(std::move(product));
      }
    }
    out = std::move(next);
  }
  return out;
}

}  // namespace

CsgProducts normalise_csg(const CsgNode& tree, const std::vector<std::string>& names) {
  CsgProducts out;
  for (const std::vector<CsgLiteral>& raw : sum_of_products(tree, false)) {
    std::vector<CsgLiteral> product;
    bool empty = false;
    for (const CsgLiteral& l : raw) {
      if (std::find(product.begin(), product.end(), l) != product.end()) continue;
      if (std::find(product.begin(), product.end(), CsgLiteral{l.solid, !l.negated}) !=
          product.end()) {
        empty = true;
      }
      product.push_back(l);
    }
    if (empty || std::find(out.begin(), out.end(), product) != out.end()) continue;
    if (std::none_of(product.begin(), product.end(),
                     [](const CsgLiteral& l) { return !l.negated; })) {
      throw CsgError(fmt::format(
          "the product '{}' has no solid that is not complemented: it is unbounded (everything "
          "outside those solids) and cannot be drawn from their faces",
          format_csg({product}, names)));
    }
    out.push_back(std::move(product));
  }
  if (out.size() > kMaxCsgProducts) {
    throw CsgError(fmt::format("the expression expands to {} products; at most {}", out.size(),
                               kMaxCsgProducts));
  }
  if (out.empty())
    throw CsgError("the expression is empty (every product holds a solid and its complement)");
  return out;
}

bool csg_contains(const CsgProducts& products, const std::vector<bool>& inside) {
  return std::any_of(products.begin(), products.end(), [&](const std::vector<CsgLiteral>& p) {
    return std::all_of(p.begin(), p.end(), [&](const CsgLiteral& l) {
      return inside[static_cast<std::size_t>(l.solid)] != l.negated;
    });
  });
}

std::string format_csg(const CsgProducts& products, const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t p = 0; p < products.size(); ++p) {
    if (p > 0) out += " | ";
    for (std::size_t k = 0; k < products[p].size(); ++k) {
      const CsgLiteral& l = products[p][k];
      if (k > 0) out += " & ";
      if (l.negated) out += "!";
      const auto s = static_cast<std::size_t>(l.solid);
      out += s < names.size() ? names[s] : fmt::format("#{}", l.solid);
    }
  }
  return out;
}

}  // namespace pp5
