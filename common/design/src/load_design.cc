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

namespace {

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  SourcePlace At(const YAML::Node& n) const { return YamlPlace(file_, n.Mark()); }

  [[noreturn]] void Fail(const YAML::Node& n, const std::string& what) const { FailAt(At(n), what); }
  [[noreturn]] void Fail(const SourcePlace& p, const std::string& what) const { FailAt(p, what); }

  std::string String(const YAML::Node& n, const std::string& what) const {
    if (!n.IsScalar()) Fail(n, what + " must be a single value");
    return n.Scalar();
  }

  // A finite number written literally (ranges, defaults, voxel size).
  double Number(const YAML::Node& n, const std::string& what) const {
    if (!n.IsScalar()) Fail(n, what + " must be a number");
    const std::string& s = n.Scalar();
    double v = 0;
    std::size_t used = 0;
    try {
      v = std::stod(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    std::string lower = s;
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (lower == ".nan" || lower == "nan") Fail(n, what + " is NaN");
    if (lower == ".inf" || lower == "-.inf" || lower == "+.inf") Fail(n, what + " is infinite");
    if (used == 0 || used != s.size()) Fail(n, what + " must be a number, got '" + s + "'");
    if (!std::isfinite(v)) Fail(n, what + " is not finite");
    return v;
  }

  void OnlyKeys(const YAML::Node& map, const std::set<std::string>& allowed, const std::string& what) const {
    for (auto it = map.begin(); it != map.end(); ++it) {
      std::string key = it->first.Scalar();
      if (!allowed.count(key)) {
        std::string list;
        for (const auto& k : allowed) list += (list.empty() ? "" : ", ") + k;
        Fail(it->first, "unknown key '" + key + "' in " + what + " (expected one of: " + list + ")");
      }
    }
  }

  Argument ToArgument(const YAML::Node& n) const {
    Argument a;
    a.place = At(n);
    if (n.IsScalar()) {
      a.kind = Argument::Kind::kScalar;
      a.text = n.Scalar();
      a.quoted = n.Tag() == "!";  // yaml-cpp tags quoted scalars "!", plain ones "?"
    } else if (n.IsSequence()) {
      a.kind = Argument::Kind::kList;
      for (const auto& item : n) a.items.push_back(ToArgument(item));
    } else if (n.IsMap()) {
      a.kind = Argument::Kind::kMap;
      for (auto it = n.begin(); it != n.end(); ++it) {
        a.keys.push_back(it->first.Scalar());
        a.items.push_back(ToArgument(it->second));
      }
    } else {
      Fail(n, "empty value");
    }
    return a;
  }

 private:
  std::string file_;
};

// Checks that an argument has the shape its schema asks for and that every
// expression in it compiles against the design's names.
void LintArgument(const Argument& a, const ArgSpec& spec, Scope& scope, const std::filesystem::path& dir) {
  auto fail = [&](const std::string& what) { throw InputError(a.place.str() + ": '" + spec.name + "' " + what); };
  auto scalar_expr = [&](const Argument& x) {
    if (x.kind != Argument::Kind::kScalar)
      throw InputError(x.place.str() + ": '" + spec.name + "' must hold numbers or expressions");
    Expression(x.text, scope, x.place);
  };
  auto tuple = [&](const Argument& x, std::size_t n) {
    if (x.kind != Argument::Kind::kList || x.items.size() != n)
      throw InputError(x.place.str() + ": '" + spec.name + "' needs [" + (n == 2 ? "x, y" : "x, y, z") + "] entries");
    for (const auto& item : x.items) scalar_expr(item);
  };
  switch (spec.shape) {
    case ArgShape::kNumber:
      scalar_expr(a);
      break;
    case ArgShape::kVec3:
      tuple(a, 3);
      break;
    case ArgShape::kVec2List:
      if (a.kind != Argument::Kind::kList || a.items.size() < 3) fail("must be a list of at least 3 [x, y] points");
      for (const auto& p : a.items) tuple(p, 2);
      break;
    case ArgShape::kVec3List:
      if (a.kind != Argument::Kind::kList || a.items.empty()) fail("must be a list of [x, y, z] points");
      for (const auto& p : a.items) tuple(p, 3);
      break;
    case ArgShape::kString:
      if (a.kind != Argument::Kind::kScalar) fail("must be a single word or path");
      break;
    case ArgShape::kNumberMap:
      if (a.kind != Argument::Kind::kMap) fail("must be a map of name: expression");
      for (const auto& item : a.items) scalar_expr(item);
      break;
    case ArgShape::kChoiceMap:
      if (a.kind != Argument::Kind::kMap) fail("must be a map of name: [value, ...]");
      for (const auto& item : a.items) {
        if (item.kind != Argument::Kind::kList || item.items.empty())
          throw InputError(item.place.str() + ": '" + spec.name + "' entries must be non-empty lists of values");
        for (const auto& x : item.items)
          if (x.kind != Argument::Kind::kScalar)
            throw InputError(x.place.str() + ": '" + spec.name + "' values must be numbers, booleans or strings");
      }
      break;
  }
  if (spec.name == "render" && a.text != "mesh" && a.text != "native" && a.text != "levelset" && a.text != "openscad")
    fail("must be mesh, levelset or openscad");
  if (spec.name == "file") {
    std::filesystem::path p = dir / a.text;
    if (!std::filesystem::is_regular_file(p)) fail("names a file that does not exist: " + p.string());
  }
  if (spec.name == "exact" && a.text != "true" && a.text != "false") fail("must be true or false");
  if (spec.name == "method" && a.text != "sdf" && a.text != "opening") fail("must be sdf or opening");
}

void LintArgs(const std::map<std::string, Argument>& args, const OpSchema& schema, const SourcePlace& place,
              const std::string& what, Scope& scope, const std::filesystem::path& dir) {
  for (const auto& spec : schema.args) {
    auto it = args.find(spec.name);
    if (it == args.end()) {
      if (spec.required) throw InputError(place.str() + ": " + what + " needs '" + spec.name + "'");
      continue;
    }
    LintArgument(it->second, spec, scope, dir);
  }
  for (const auto& [key, arg] : args) {
    bool known = false;
    for (const auto& spec : schema.args) known = known || spec.name == key;
    if (!known) throw InputError(arg.place.str() + ": unknown argument '" + key + "' for " + what);
  }
}

Node ReadNode(const Reader& r, const YAML::Node& y, Scope& scope, const std::filesystem::path& dir, int depth) {
  if (depth > 200) r.Fail(y, "tree is nested more than 200 levels deep");
  if (!y.IsMap()) r.Fail(y, "a tree node must be a map with an 'op' key");
  Node node;
  node.place = r.At(y);
  if (!y["op"]) r.Fail(y, "tree node has no 'op'");
  node.op = r.String(y["op"], "op");
  const auto& ops = OperationSchemas();
  auto schema_it = ops.find(node.op);
  if (schema_it == ops.end()) r.Fail(y["op"], "unknown node type '" + node.op + "'");
  for (auto it = y.begin(); it != y.end(); ++it) {
    std::string key = it->first.Scalar();
    if (key == "op") continue;
    if (key == "name") {
      node.name = r.String(it->second, "name");
    } else if (key == "children") {
      const YAML::Node list = it->second;  // a copy: the iterator yields temporaries
      if (!list.IsSequence()) r.Fail(list, "'children' must be a list of nodes");
      for (std::size_t i = 0; i < list.size(); ++i)
        node.children.push_back(ReadNode(r, list[i], scope, dir, depth + 1));
    } else {
      node.args[key] = r.ToArgument(it->second);
    }
  }
  const OpSchema& schema = schema_it->second;
  int n = static_cast<int>(node.children.size());
  if (n < schema.min_children || (schema.max_children >= 0 && n > schema.max_children)) {
    std::string want = schema.max_children == 0  ? "no children"
                       : schema.max_children < 0 ? "at least " + std::to_string(schema.min_children) + " children"
                                                 : std::to_string(schema.max_children) + " children";
    r.Fail(node.place, "'" + node.op + "' takes " + want + ", got " + std::to_string(n));
  }
  LintArgs(node.args, schema, node.place, "'" + node.op + "'", scope, dir);
  if (auto c = node.args.find("choices"); c != node.args.end()) {
    auto set = node.args.find("set");
    for (std::size_t i = 0; i < c->second.keys.size(); ++i)
      if (set == node.args.end() ||
          std::find(set->second.keys.begin(), set->second.keys.end(), c->second.keys[i]) == set->second.keys.end())
        r.Fail(c->second.items[i].place,
               "choices for '" + c->second.keys[i] + "' need an entry in 'set' giving the index");
  }
  return node;
}

void CheckUnique(const Reader& r, std::set<std::string>& seen, const std::string& name, const YAML::Node& at) {
  if (name.empty() || !(std::isalpha(static_cast<unsigned char>(name[0])) || name[0] == '_'))
    r.Fail(at, "parameter name '" + name + "' must start with a letter");
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_'))
      r.Fail(at, "parameter name '" + name + "' may use only letters, digits and _");
  if (name == "pi") r.Fail(at, "'pi' is reserved");
  if (!seen.insert(name).second) r.Fail(at, "parameter '" + name + "' is declared twice");
}

// A list of points each with `n` expressions (motions: [x, y, z] or
// [ax, ay, az, degrees]); every expression must compile.
void LintTuples(const Argument& a, std::size_t n, const std::string& what, Scope& scope) {
  if (a.kind != Argument::Kind::kList) throw InputError(a.place.str() + ": " + what + " must be a list");
  for (const auto& p : a.items) {
    if (p.kind != Argument::Kind::kList || p.items.size() != n)
      throw InputError(p.place.str() + ": " + what + " needs entries of " + std::to_string(n) + " numbers");
    for (const auto& x : p.items) {
      if (x.kind != Argument::Kind::kScalar)
        throw InputError(x.place.str() + ": " + what + " must hold numbers or expressions");
      Expression(x.text, scope, x.place);
    }
  }
}

// The objects of a reconfigurable: name -> tree.
void ReadObjects(const Reader& r, const YAML::Node& root, Design& d, Scope& scope, const std::filesystem::path& dir) {
  if (!root["objects"]) return;
  std::set<std::string> object_names;
  const YAML::Node objects = root["objects"];
  if (!objects.IsMap() || objects.size() == 0) r.Fail(objects, "'objects' must be a map of name: tree node");
  for (auto it = objects.begin(); it != objects.end(); ++it) {
    DesignObject o;
    o.name = it->first.Scalar();
    o.place = r.At(it->first);
    if (!object_names.insert(o.name).second) r.Fail(it->first, "object '" + o.name + "' is declared twice");
    o.tree = ReadNode(r, it->second, scope, dir, 1);
    d.objects.push_back(std::move(o));
  }
}

void ReadStates(const Reader& r, const YAML::Node& root, Design& d) {
  if (!root["states"]) return;
  std::set<std::string> states;
  const YAML::Node list = root["states"];
  if (!list.IsSequence() || list.size() == 0) r.Fail(list, "'states' must be a list of state names");
  for (const auto& s : list) {
    std::string name = r.String(s, "state");
    if (!states.insert(name).second) r.Fail(s, "state '" + name + "' is listed twice");
    d.states.push_back(name);
  }
}

// One object's motion on a transition: translation, rotation, pivot.
ObjectMotion ReadMotion(const Reader& r, const YAML::Node& key, const YAML::Node& spec, const Design& d, Scope& scope) {
  ObjectMotion m;
  m.object = key.Scalar();
  m.place = r.At(key);
  if (!d.FindObject(m.object)) r.Fail(key, "unknown object '" + m.object + "'");
  if (!spec.IsMap()) r.Fail(spec, "the motion of '" + m.object + "' must be a map");
  r.OnlyKeys(spec, {"translation", "rotation", "pivot"}, "motion of '" + m.object + "'");
  if (spec["translation"]) {
    m.translation = r.ToArgument(spec["translation"]);
    m.has_translation = true;
    LintTuples(m.translation, 3, "'translation'", scope);
    std::size_t n = m.translation.items.size();
    if (n != 2 && n != 4)
      r.Fail(spec["translation"], "'translation' needs 2 points (a line) or 4 Bezier control points");
  }
  if (spec["rotation"]) {
    m.rotation = r.ToArgument(spec["rotation"]);
    m.has_rotation = true;
    LintTuples(m.rotation, 4, "'rotation' keys [axis x, axis y, axis z, degrees]", scope);
    if (m.rotation.items.empty()) r.Fail(spec["rotation"], "'rotation' needs at least one key");
  }
  if (spec["pivot"]) {
    m.pivot = r.ToArgument(spec["pivot"]);
    m.has_pivot = true;
    Argument wrapped;
    wrapped.kind = Argument::Kind::kList;
    wrapped.items = {m.pivot};
    LintTuples(wrapped, 3, "'pivot'", scope);
  }
  return m;
}

// Transitions between states, each from the first state or one reached before.
void ReadTransitions(const Reader& r, const YAML::Node& root, Design& d, Scope& scope) {
  if (!root["transitions"]) return;
  const YAML::Node list = root["transitions"];
  if (!list.IsSequence()) r.Fail(list, "'transitions' must be a list");
  if (d.states.empty()) r.Fail(list, "transitions need a 'states' list");
  const std::set<std::string> states(d.states.begin(), d.states.end());
  std::set<std::string> reached = {d.states.front()}, names;
  for (const auto& y : list) {
    if (!y.IsMap()) r.Fail(y, "a transition is a map with from, to and motions");
    r.OnlyKeys(y, {"name", "from", "to", "motions"}, "transition");
    Transition t;
    t.place = r.At(y);
    if (!y["from"] || !y["to"]) r.Fail(y, "a transition needs 'from' and 'to'");
    t.from = r.String(y["from"], "from");
    t.to = r.String(y["to"], "to");
    if (!states.count(t.from)) r.Fail(y["from"], "unknown state '" + t.from + "'");
    if (!states.count(t.to)) r.Fail(y["to"], "unknown state '" + t.to + "'");
    if (!reached.count(t.from))
      r.Fail(y["from"], "state '" + t.from + "' is not the first state nor reached by an earlier transition");
    reached.insert(t.to);
    t.name = y["name"] ? r.String(y["name"], "name") : t.from + "->" + t.to;
    if (!names.insert(t.name).second) r.Fail(y, "transition '" + t.name + "' is declared twice");
    if (y["motions"]) {
      const YAML::Node motions = y["motions"];
      if (!motions.IsMap()) r.Fail(motions, "'motions' must be a map of object: motion");
      for (auto it = motions.begin(); it != motions.end(); ++it)
        t.motions.push_back(ReadMotion(r, it->first, it->second, d, scope));
    }
    d.transitions.push_back(std::move(t));
  }
}

// The objects, states and transitions of a reconfigurable (Reconfigurables).
void ReadReconfigurable(const Reader& r, const YAML::Node& root, Design& d, Scope& scope,
                        const std::filesystem::path& dir) {
  ReadObjects(r, root, d, scope, dir);
  ReadStates(r, root, d);
  ReadTransitions(r, root, d, scope);
}

// Every `object` and `carve_swept` node names a declared object and
// transition, and no object contains itself (through object nodes or the
// moving object of a carve).
void LintReferences(const Design& d) {
  std::map<std::string, std::set<std::string>> uses;  // object -> objects its tree needs
  std::function<void(const Node&, std::set<std::string>&)> walk = [&](const Node& n, std::set<std::string>& out) {
    auto text = [&](const char* key) -> const Argument* {
      auto it = n.args.find(key);
      return it == n.args.end() ? nullptr : &it->second;
    };
    if (n.op == "object") {
      const Argument* a = text("object");
      if (!d.FindObject(a->text)) throw InputError(a->place.str() + ": unknown object '" + a->text + "'");
      out.insert(a->text);
    }
    if (n.op == "carve_swept") {
      const Argument* moving = text("moving");
      if (!d.FindObject(moving->text))
        throw InputError(moving->place.str() + ": unknown object '" + moving->text + "'");
      out.insert(moving->text);
      if (const Argument* frame = text("frame")) {
        if (!d.FindObject(frame->text)) throw InputError(frame->place.str() + ": unknown object '" + frame->text + "'");
        if (frame->text == moving->text)
          throw InputError(frame->place.str() + ": carve_swept 'frame' and 'moving' are the same object");
      }
      const Argument* t = text("transition");
      if (!d.FindTransition(t->text)) throw InputError(t->place.str() + ": unknown transition '" + t->text + "'");
    }
    for (const auto& c : n.children) walk(c, out);
  };
  for (const auto& o : d.objects) walk(o.tree, uses[o.name]);
  std::set<std::string> root_uses;
  walk(d.tree, root_uses);
  // Depth-first search for a cycle among objects.
  std::map<std::string, int> state;  // 0 new, 1 on the stack, 2 done
  std::function<void(const std::string&)> visit = [&](const std::string& name) {
    state[name] = 1;
    for (const auto& next : uses[name]) {
      if (state[next] == 1)
        throw InputError(d.FindObject(name)->place.str() + ": object '" + name + "' depends on itself through '" +
                         next + "'");
      if (state[next] == 0) visit(next);
    }
    state[name] = 2;
  };
  for (const auto& o : d.objects)
    if (state[o.name] == 0) visit(o.name);
}

}  // namespace

Design LoadDesign(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open design file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path.string() + ": cannot read design file");
  return ParseDesign(buffer.str(), path);
}

namespace {

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
