// Reads a design's geometry tree and a reconfigurable's objects, states and
// transitions (docs/design-format.md, "tree" and "Reconfigurables").
#include <algorithm>
#include <functional>
#include <set>

#include "design_reader.h"
#include "node_schema.h"

namespace fabatlas::design {
namespace {

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

}  // namespace

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

}  // namespace fabatlas::design
