// A model's bodies and colour regions as CSG programs (fabatlas/scad/part_trees.h).
#include "fabatlas/scad/part_trees.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace fabatlas::scad {
namespace {

struct Colour {
  bool set = false;
  std::array<double, 4> rgba{};
  bool operator==(const Colour& o) const { return set == o.set && (!set || rgba == o.rgba); }
};

// One colour's pieces of material, in tree order.
struct Region {
  Colour colour;
  std::vector<std::string> pieces;
};

// color(c)'s colour; unset when OpenSCAD could not parse it ([-1, -1, -1, 1]).
Colour ColourOf(const CsgNode& n) {
  const CsgValue* c = nullptr;
  if (auto it = n.args.find("c"); it != n.args.end())
    c = &it->second;
  else if (!n.positional.empty())
    c = &n.positional[0];
  Colour out;
  if (!c || c->type != CsgValue::Type::kVector || c->items.size() < 3) return out;
  out.rgba = {0, 0, 0, 1};
  for (std::size_t k = 0; k < 4 && k < c->items.size(); ++k) {
    if (c->items[k].type != CsgValue::Type::kNumber || c->items[k].number < 0) return {};
    out.rgba[k] = std::min(1.0, c->items[k].number);
  }
  out.set = true;
  return out;
}

// The node's text up to its children: canonical = header + "{" + children + "}".
std::string Header(const CsgNode& n) {
  if (n.children.empty()) return n.canonical.substr(0, n.canonical.size() - 1);  // drop ';'
  std::size_t kids = 2;
  for (const auto& c : n.children) kids += c.canonical.size();
  return n.canonical.substr(0, n.canonical.size() - kids);
}

void Add(std::vector<Region>& regions, const Colour& colour, std::string piece) {
  for (Region& r : regions)
    if (r.colour == colour) {
      r.pieces.push_back(std::move(piece));
      return;
    }
  regions.push_back({colour, {std::move(piece)}});
}

std::string Joined(const Region& r) {
  if (r.pieces.size() == 1) return r.pieces[0];
  std::string out = "union(){";
  for (const auto& p : r.pieces) out += p;
  return out + "}";
}

// The innermost colour on the way to n's first coloured leaf, if any.
Colour FirstColour(const CsgNode& n) {
  for (const auto& c : n.children) {
    Colour inner = FirstColour(c);
    if (inner.set) return inner;
    if (c.name == "color") {
      Colour own = ColourOf(c);
      if (own.set) return own;
    }
  }
  return {};
}

std::vector<Region> Regions(const CsgNode& n, const Colour& around);

std::vector<Region> Merged(const std::vector<CsgNode>& children, const Colour& around) {
  std::vector<Region> out;
  for (const auto& c : children)
    for (Region& r : Regions(c, around))
      for (std::string& p : r.pieces) Add(out, r.colour, std::move(p));
  return out;
}

std::vector<Region> Regions(const CsgNode& n, const Colour& around) {
  if (n.name == "color") {
    const Colour own = ColourOf(n);
    return Merged(n.children, own.set ? own : around);
  }
  if (n.name == "group" || n.name == "union" || n.name == "render") return Merged(n.children, around);
  if (n.name == "multmatrix") {
    std::vector<Region> out = Merged(n.children, around);
    const std::string header = Header(n);
    for (Region& r : out)
      for (std::string& p : r.pieces) p = header + "{" + p + "}";
    return out;
  }
  if ((n.name == "difference" || n.name == "intersection") && !n.children.empty()) {
    std::string rest;
    for (std::size_t i = 1; i < n.children.size(); ++i) rest += n.children[i].canonical;
    std::vector<Region> out;
    for (Region& r : Regions(n.children[0], around))
      out.push_back({r.colour, {Header(n) + "{" + Joined(r) + rest + "}"}});
    return out;
  }
  const Colour inner = FirstColour(n);
  return {{inner.set ? inner : around, {n.canonical}}};
}

}  // namespace

std::vector<PartTree> PartTrees(const CsgNode& root) {
  std::vector<PartTree> out;
  for (std::size_t b = 0; b < root.children.size(); ++b)
    for (const Region& r : Regions(root.children[b], Colour{}))
      out.push_back({static_cast<int>(b) + 1, r.colour.set, r.colour.rgba, Joined(r)});
  return out;
}

std::string HexColour(const std::array<double, 4>& rgba) {
  char text[16];
  auto byte = [](double v) { return static_cast<int>(std::lround(std::clamp(v, 0.0, 1.0) * 255)); };
  std::snprintf(text, sizeof text, "#%02x%02x%02x", byte(rgba[0]), byte(rgba[1]), byte(rgba[2]));
  std::string out = text;
  if (rgba[3] < 1) {
    std::snprintf(text, sizeof text, "%02x", byte(rgba[3]));
    out += text;
  }
  return out;
}

}  // namespace fabatlas::scad
