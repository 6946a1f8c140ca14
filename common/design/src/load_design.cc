// Reads and lints a design file (docs/design-format.md).
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "expression.h"
#include "fabatlas/design/design.h"
#include "fabatlas/error.h"
#include "fabatlas/yaml_place.h"
#include "design_reader.h"
#include "node_schema.h"

namespace fabatlas::design {

const ExposedParameter* Design::FindExposed(const std::string& name) const {
  for (const auto& p : exposed)
    if (p.name == name) return &p;
  return nullptr;
}

const DesignObject* Design::FindObject(const std::string& name) const {
  for (const auto& o : objects)
    if (o.name == name) return &o;
  return nullptr;
}

const Transition* Design::FindTransition(const std::string& name) const {
  for (const auto& t : transitions)
    if (t.name == name) return &t;
  return nullptr;
}

Design LoadDesign(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open design file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path.string() + ": cannot read design file");
  return ParseDesign(buffer.str(), path);
}

namespace {

void CheckUnique(const Reader& r, std::set<std::string>& seen, const std::string& name, const YAML::Node& at) {
  if (name.empty() || !(std::isalpha(static_cast<unsigned char>(name[0])) || name[0] == '_'))
    r.Fail(at, "parameter name '" + name + "' must start with a letter");
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_'))
      r.Fail(at, "parameter name '" + name + "' may use only letters, digits and _");
  if (name == "pi") r.Fail(at, "'pi' is reserved");
  if (!seen.insert(name).second) r.Fail(at, "parameter '" + name + "' is declared twice");
}

// One exposed parameter: real or integer (min, max, default) or enum (values).
ExposedParameter ReadExposedParameter(const Reader& r, const YAML::Node& key, const YAML::Node& spec) {
  ExposedParameter p;
  p.name = key.Scalar();
  p.place = r.At(key);
  if (!spec.IsMap()) r.Fail(spec, "parameter '" + p.name + "' must be a map with type, min, max");
  r.OnlyKeys(spec, {"type", "min", "max", "default", "values", "description", "group"}, "parameter '" + p.name + "'");
  if (spec["description"]) p.description = r.String(spec["description"], "description");
  if (spec["group"]) p.group = r.String(spec["group"], "group");
  std::string type = spec["type"] ? r.String(spec["type"], "type") : "real";
  if (type == "real" || type == "integer") {
    p.kind = type == "real" ? ParameterKind::kReal : ParameterKind::kInteger;
    if (!spec["min"] || !spec["max"]) r.Fail(spec, "parameter '" + p.name + "' needs min and max");
    p.min = r.Number(spec["min"], "min");
    p.max = r.Number(spec["max"], "max");
    if (p.min > p.max) r.Fail(spec["min"], "parameter '" + p.name + "' has min > max");
    if (p.kind == ParameterKind::kInteger && (p.min != std::floor(p.min) || p.max != std::floor(p.max)))
      r.Fail(spec, "integer parameter '" + p.name + "' needs whole-number min and max");
    p.default_value = spec["default"] ? r.Number(spec["default"], "default") : 0.5 * (p.min + p.max);
    if (p.kind == ParameterKind::kInteger) p.default_value = std::round(p.default_value);
    if (p.default_value < p.min || p.default_value > p.max)
      r.Fail(spec["default"], "default of '" + p.name + "' is outside [min, max]");
  } else if (type == "enum") {
    p.kind = ParameterKind::kEnumerated;
    if (!spec["values"] || !spec["values"].IsSequence() || spec["values"].size() == 0)
      r.Fail(spec, "enum parameter '" + p.name + "' needs a non-empty 'values' list");
    for (const auto& v : spec["values"]) p.labels.push_back(r.String(v, "enum value"));
    p.min = 0;
    p.max = static_cast<double>(p.labels.size() - 1);
    p.default_value = 0;
    if (spec["default"]) {
      std::string def = r.String(spec["default"], "default");
      auto f = std::find(p.labels.begin(), p.labels.end(), def);
      if (f == p.labels.end())
        r.Fail(spec["default"], "default '" + def + "' is not one of the values of '" + p.name + "'");
      p.default_value = static_cast<double>(f - p.labels.begin());
    }
  } else {
    r.Fail(spec["type"], "unknown parameter type '" + type + "' (expected real, integer or enum)");
  }
  return p;
}

void ReadExposed(const Reader& r, const YAML::Node& root, Design& d, std::set<std::string>& names) {
  // `parameters: {}` exposes nothing: the design is one sample (a model
  // imported without Customizer annotations, docs/design-format.md).
  if (!root["parameters"] || !root["parameters"].IsMap())
    r.Fail(root["parameters"] ? root["parameters"] : root,
           "design needs a 'parameters' map of exposed parameters ('parameters: {}' for none: one sample)");
  for (auto it = root["parameters"].begin(); it != root["parameters"].end(); ++it) {
    CheckUnique(r, names, it->first.Scalar(), it->first);
    d.exposed.push_back(ReadExposedParameter(r, it->first, it->second));
  }
}

// Mutable parameters, solved for: min, max, default.
void ReadVariables(const Reader& r, const YAML::Node& root, Design& d, std::set<std::string>& names) {
  if (!root["variables"]) return;
  if (!root["variables"].IsMap()) r.Fail(root["variables"], "'variables' must be a map");
  for (auto it = root["variables"].begin(); it != root["variables"].end(); ++it) {
    MutableParameter m;
    m.name = it->first.Scalar();
    m.place = r.At(it->first);
    CheckUnique(r, names, m.name, it->first);
    const YAML::Node spec = it->second;  // a copy: the iterator yields temporaries
    if (!spec.IsMap()) r.Fail(spec, "variable '" + m.name + "' must be a map with min, max, default");
    r.OnlyKeys(spec, {"min", "max", "default"}, "variable '" + m.name + "'");
    if (spec["min"]) m.min = r.Number(spec["min"], "min");
    if (spec["max"]) m.max = r.Number(spec["max"], "max");
    if (m.min > m.max) r.Fail(spec["min"], "variable '" + m.name + "' has min > max");
    m.default_value = spec["default"]
                          ? r.Number(spec["default"], "default")
                          : (spec["min"] && spec["max"] ? 0.5 * (m.min + m.max) : std::clamp(0.0, m.min, m.max));
    if (m.default_value < m.min || m.default_value > m.max)
      r.Fail(spec["default"], "default of '" + m.name + "' is outside [min, max]");
    d.mutables.push_back(m);
  }
}

// Constraints: `lhs REL rhs` with exactly one of ==, <=, >=.
void ReadConstraints(const Reader& r, const YAML::Node& root, Design& d, Scope& scope) {
  if (!root["constraints"]) return;
  if (!root["constraints"].IsSequence()) r.Fail(root["constraints"], "'constraints' must be a list of relations");
  for (const auto& c : root["constraints"]) {
    Constraint k;
    k.text = r.String(c, "constraint");
    k.place = r.At(c);
    struct Op {
      const char* token;
      Relation rel;
      bool swap;
    };
    const Op ops[] = {
        {"==", Relation::kEqual, false}, {"<=", Relation::kLessEqual, false}, {">=", Relation::kGreaterEqual, false}};
    bool found = false;
    for (const auto& op : ops) {
      auto pos = k.text.find(op.token);
      if (pos == std::string::npos) continue;
      if (found || k.text.find(op.token, pos + 2) != std::string::npos)
        r.Fail(c, "constraint '" + k.text + "' must hold exactly one of ==, <=, >=");
      found = true;
      k.lhs = k.text.substr(0, pos);
      k.rhs = k.text.substr(pos + 2);
      k.relation = op.rel;
    }
    if (!found) r.Fail(c, "constraint '" + k.text + "' needs one of ==, <=, >=");
    Expression(k.lhs, scope, k.place);
    Expression(k.rhs, scope, k.place);
    d.constraints.push_back(k);
  }
}

// A check's `repair_with`: exposed real parameters, "a, b".
void LintRepairWith(const Reader& r, const YAML::Node& c, const CheckSpec& check, const Design& d) {
  std::string names = check.args.at("repair_with").text + ",", name;
  for (const char ch : names) {
    if (ch != ',' && ch != ' ') {
      name += ch;
      continue;
    }
    if (name.empty()) continue;
    const ExposedParameter* p = d.FindExposed(name);
    if (!p || p->kind != ParameterKind::kReal)
      r.Fail(c["repair_with"], "repair_with: '" + name + "' is not an exposed real parameter");
    name.clear();
  }
}

// One check: a type name, or a map with type, name and the type's arguments.
CheckSpec ReadCheck(const Reader& r, const YAML::Node& c, const Design& d, Scope& scope,
                    const std::filesystem::path& dir) {
  CheckSpec check;
  check.place = r.At(c);
  if (c.IsScalar()) {
    check.type = c.Scalar();
  } else if (c.IsMap()) {
    if (!c["type"]) r.Fail(c, "a check needs a 'type'");
    check.type = r.String(c["type"], "type");
    for (auto it = c.begin(); it != c.end(); ++it) {
      std::string key = it->first.Scalar();
      if (key == "type") continue;
      if (key == "name")
        check.name = r.String(it->second, "name");
      else
        check.args[key] = r.ToArgument(it->second);
    }
  } else {
    r.Fail(c, "a check is a type name or a map with 'type'");
  }
  const auto& schemas = CheckSchemas();
  auto it = schemas.find(check.type);
  if (it == schemas.end()) r.Fail(c, "unknown check type '" + check.type + "'");
  if (check.name.empty()) check.name = check.type;
  LintArgs(check.args, it->second, check.place, "check '" + check.type + "'", scope, dir);
  if (check.type == "assembly_feasible" || check.type == "assembly_stable" || check.type == "target_reached") {
    std::function<bool(const Node&)> has = [&](const Node& n) {
      if (n.op == "assembly") return true;
      for (const auto& k : n.children)
        if (has(k)) return true;
      return false;
    };
    if (!has(d.tree)) r.Fail(c, "check '" + check.type + "' needs an 'assembly' node in the tree");
  }
  // Automatic resolution's degrees of freedom: exposed real parameters.
  if (check.args.count("repair_with")) LintRepairWith(r, c, check, d);
  return check;
}

void ReadChecks(const Reader& r, const YAML::Node& root, Design& d, Scope& scope, const std::filesystem::path& dir) {
  if (!root["checks"]) return;
  if (!root["checks"].IsSequence()) r.Fail(root["checks"], "'checks' must be a list");
  for (const auto& c : root["checks"]) d.checks.push_back(ReadCheck(r, c, d, scope, dir));
}

void ReadProperties(const Reader& r, const YAML::Node& root, Design& d) {
  if (!root["properties"]) {
    d.properties = {"volume"};
    return;
  }
  if (!root["properties"].IsSequence()) r.Fail(root["properties"], "'properties' must be a list");
  for (const auto& p : root["properties"]) {
    std::string name = r.String(p, "property");
    const auto& known = PropertyNames();
    if (std::find(known.begin(), known.end(), name) == known.end())
      r.Fail(p, "unknown property '" + name + "' (expected volume, area or bbox)");
    d.properties.push_back(name);
  }
}

// One preset's value of an exposed parameter; enum values by label.
double PresetValue(const Reader& r, const YAML::Node& key, const YAML::Node& value, const Design& d,
                   const std::string& preset) {
  const std::string name = key.Scalar();
  const ExposedParameter* p = d.FindExposed(name);
  if (!p) r.Fail(key, "preset '" + preset + "': '" + name + "' is not an exposed parameter");
  if (p->kind == ParameterKind::kEnumerated) {
    const std::string label = r.String(value, "preset value");
    auto f = std::find(p->labels.begin(), p->labels.end(), label);
    if (f == p->labels.end())
      r.Fail(value, "preset '" + preset + "': '" + label + "' is not one of the values of '" + name + "'");
    return static_cast<double>(f - p->labels.begin());
  }
  const double x = r.Number(value, "preset value");
  if (x < p->min || x > p->max) r.Fail(value, "preset '" + preset + "': " + name + " is outside [min, max]");
  if (p->kind == ParameterKind::kInteger && x != std::round(x))
    r.Fail(value, "preset '" + preset + "': " + name + " takes whole numbers");
  return x;
}

// presets: {name: {parameter: value, ...}}; the rest at their defaults.
void ReadPresets(const Reader& r, const YAML::Node& root, Design& d) {
  if (!root["presets"]) return;
  if (!root["presets"].IsMap()) r.Fail(root["presets"], "'presets' must be a map of name: {parameter: value}");
  for (auto it = root["presets"].begin(); it != root["presets"].end(); ++it) {
    Preset preset;
    preset.name = it->first.Scalar();
    preset.place = r.At(it->first);
    const YAML::Node values = it->second;  // a copy: the iterator yields temporaries
    if (!values.IsMap()) r.Fail(values, "preset '" + preset.name + "' must be a map of parameter: value");
    for (const auto& p : d.exposed) preset.values[p.name] = p.default_value;
    for (auto v = values.begin(); v != values.end(); ++v)
      preset.values[v->first.Scalar()] = PresetValue(r, v->first, v->second, d, preset.name);
    d.presets.push_back(std::move(preset));
  }
}

// fixed: {name: {value, description, group, why}}: shown, never sampled.
void ReadFixed(const Reader& r, const YAML::Node& root, Design& d, std::set<std::string>& names) {
  if (!root["fixed"]) return;
  if (!root["fixed"].IsMap()) r.Fail(root["fixed"], "'fixed' must be a map of name: {value, description, group, why}");
  for (auto it = root["fixed"].begin(); it != root["fixed"].end(); ++it) {
    FixedParameter f;
    f.name = it->first.Scalar();
    f.place = r.At(it->first);
    // The model's names (OpenSCAD's rules, not the expressions'): unique.
    if (f.name.empty() || !names.insert(f.name).second)
      r.Fail(it->first, "parameter '" + f.name + "' is declared twice");
    const YAML::Node spec = it->second;  // a copy: the iterator yields temporaries
    if (!spec.IsMap() || !spec["value"]) r.Fail(spec, "fixed parameter '" + f.name + "' must be a map with a value");
    r.OnlyKeys(spec, {"value", "description", "group", "why"}, "fixed parameter '" + f.name + "'");
    f.value = r.String(spec["value"], "value");
    if (spec["description"]) f.description = r.String(spec["description"], "description");
    if (spec["group"]) f.group = r.String(spec["group"], "group");
    if (spec["why"]) f.why = r.String(spec["why"], "why");
    d.fixed.push_back(std::move(f));
  }
}

}  // namespace

Design ParseDesign(const std::string& text, const std::filesystem::path& path) {
  const std::string file = path.string();
  Design d;
  d.file = path;
  d.canonical_text = text;
  Reader r(file);

  YAML::Node root;
  try {
    root = YAML::Load(d.canonical_text);
  } catch (const YAML::Exception& e) {
    FailAt(YamlPlace(file, e.mark), "malformed YAML: " + e.msg);
  }
  if (!root.IsMap()) throw InputError(file + ": a design file must be a YAML map (name, parameters, tree, ...)");
  r.OnlyKeys(root,
             {"name", "voxel_size", "parameters", "variables", "constraints", "tree", "checks", "properties",
              "description", "objects", "states", "transitions", "presets", "fixed"},
             "design");

  d.name = root["name"] ? r.String(root["name"], "name") : path.stem().string();
  if (root["voxel_size"]) {
    d.voxel_size = r.Number(root["voxel_size"], "voxel_size");
    if (d.voxel_size <= 0) r.Fail(root["voxel_size"], "voxel_size must be positive");
  }

  std::set<std::string> names;
  ReadExposed(r, root, d, names);
  ReadVariables(r, root, d, names);
  Scope scope(ParameterNames(d));
  ReadConstraints(r, root, d, scope);
  ReadReconfigurable(r, root, d, scope, path.parent_path());
  if (!root["tree"]) r.Fail(root, "design has no 'tree'");
  d.tree = ReadNode(r, root["tree"], scope, path.parent_path(), 0);
  LintReferences(d);
  ReadChecks(r, root, d, scope, path.parent_path());
  ReadProperties(r, root, d);
  ReadPresets(r, root, d);
  ReadFixed(r, root, d, names);
  return d;
}

}  // namespace fabatlas::design
