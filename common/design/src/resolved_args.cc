// A node's arguments evaluated at a sample (ResolvedArgs, operations.h):
// expressions, file digests and the OpenSCAD literals of an `openscad`
// node's `set`, and their canonical text ρ (Fab Forms Sec. 6).
#include <cmath>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/exact_decimal.h"
#include "fabatlas/scad/customizer.h"
#include "fabatlas/sha256.h"
#include "node_schema.h"
#include "operations.h"
#include "tree_evaluation.h"

namespace fabatlas::design {
namespace {

bool IsScadNumberOrBoolean(const std::string& s) {
  if (s == "true" || s == "false") return true;
  char* end = nullptr;
  double v = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size() && std::isfinite(v) &&
         s.find_first_not_of("0123456789.-+eE") == std::string::npos;
}

// Digest of a file's bytes, remembered per path for the process lifetime.
std::string FileDigest(const std::filesystem::path& p) {
  static std::mutex mutex;
  static std::map<std::string, std::string> digests;
  std::lock_guard<std::mutex> lock(mutex);
  auto it = digests.find(p.string());
  if (it != digests.end()) return it->second;
  std::ifstream in(p, std::ios::binary);
  if (!in) throw InputError(p.string() + ": cannot read file");
  std::stringstream ss;
  ss << in.rdbuf();
  return digests[p.string()] = Sha256Hex(ss.str());
}

// The OpenSCAD literal a `set` entry of an openscad node passes: the value
// its `choices` list holds at index `value` (quoted YAML scalars as OpenSCAD
// strings, plain ones as written), else the number.
std::string OpenScadLiteral(const Node& node, const std::string& key, double value, const SourcePlace& place) {
  auto c = node.args.find("choices");
  if (c != node.args.end()) {
    for (std::size_t i = 0; i < c->second.keys.size(); ++i) {
      if (c->second.keys[i] != key) continue;
      const auto& options = c->second.items[i].items;
      if (value != std::round(value) || value < 0 || value >= static_cast<double>(options.size()))
        throw SampleFailure(kNoGeometry, place.str() + ": '" + key + "' = " + ExactDecimal(value) +
                                             " is not an index of its " + std::to_string(options.size()) + " choices");
      const Argument& chosen = options[static_cast<std::size_t>(value)];
      return chosen.quoted || !IsScadNumberOrBoolean(chosen.text) ? scad::QuoteScadString(chosen.text) : chosen.text;
    }
  }
  return scad::FormatScadNumber(value);
}

}  // namespace

ResolvedArgs TreeEvaluation::Resolve(const Node& node) {
  ResolvedArgs r;
  const OpSchema& schema = OperationSchemas().at(node.op);
  for (const auto& spec : schema.args) {
    auto it = node.args.find(spec.name);
    if (it == node.args.end()) continue;
    const Argument& a = it->second;
    ResolvedArgs::Value v;
    v.place = a.place;
    auto number = [&](const Argument& x) {
      double value = Expression(x.text, scope_, x.place).Evaluate();
      if (!std::isfinite(value))
        throw SampleFailure(kNoGeometry, x.place.str() + ": '" + spec.name + "' evaluates to " + ExactDecimal(value));
      return value;
    };
    switch (spec.shape) {
      case ArgShape::kNumber:
        v.numbers = {number(a)};
        break;
      case ArgShape::kVec3:
        for (const auto& x : a.items) v.numbers.push_back(number(x));
        break;
      case ArgShape::kVec2List:
      case ArgShape::kVec3List:
        for (const auto& p : a.items)
          for (const auto& x : p.items) v.numbers.push_back(number(x));
        break;
      case ArgShape::kString:
        v.text = a.text;
        if (spec.name == "file") v.digest = FileDigest(design_.file.parent_path() / a.text);
        break;
      case ArgShape::kNumberMap:
        for (std::size_t i = 0; i < a.items.size(); ++i) {
          v.keys.push_back(a.keys[i]);
          v.numbers.push_back(number(a.items[i]));
          v.literals.push_back(OpenScadLiteral(node, a.keys[i], v.numbers.back(), a.items[i].place));
        }
        break;
      case ArgShape::kChoiceMap:
        continue;  // read through `set` (OpenScadLiteral)
    }
    r.values[spec.name] = std::move(v);
  }
  return r;
}

std::string ResolvedArgs::Canonical() const {
  std::string out;
  for (const auto& [name, v] : values) {
    out += name + "=";
    for (std::size_t i = 0; i < v.numbers.size(); ++i) {
      if (i < v.keys.size()) out += v.keys[i] + ":";
      out += ExactDecimal(v.numbers[i]) + ",";
      if (i < v.literals.size()) out += v.literals[i] + ",";
    }
    out += v.text + (v.digest.empty() ? "" : "@" + v.digest) + ";";
  }
  return out;
}

double ResolvedArgs::Number(const std::string& name, double fallback) const {
  auto it = values.find(name);
  return it == values.end() || it->second.numbers.empty() ? fallback : it->second.numbers[0];
}

geometry::Vec3 ResolvedArgs::Vec3(const std::string& name) const {
  const auto& n = values.at(name).numbers;
  return {n[0], n[1], n[2]};
}

std::string ResolvedArgs::Text(const std::string& name, const std::string& fallback) const {
  auto it = values.find(name);
  return it == values.end() ? fallback : it->second.text;
}

}  // namespace fabatlas::design
