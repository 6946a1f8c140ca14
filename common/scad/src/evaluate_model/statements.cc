// Statements of evaluate_model.h's evaluator (evaluator.h): scopes'
// definitions and assignments, blocks, if, for, intersection_for, let,
// modifiers, user modules and children() (built-in modules:
// builtin_modules.h).
#include <cmath>

#include "builtin_modules.h"
#include "evaluator.h"

namespace fabatlas::scad::internal {

void Override(std::vector<StmtPtr>& program, const std::string& name, const ExprPtr& value) {
  for (StmtPtr& s : program) {
    if (s->kind != Stmt::Kind::kAssign || s->name != name) continue;
    auto copy = std::make_shared<Stmt>(*s);
    copy->expr = value;
    s = copy;
    return;
  }
  auto s = std::make_shared<Stmt>();
  s->kind = Stmt::Kind::kAssign;
  s->name = name;
  s->expr = value;
  program.push_back(s);
}

void Evaluator::Run(const std::vector<StmtPtr>& body, Scope& scope, std::vector<CsgOut>& out) {
  Define(body, scope);
  for (const StmtPtr& s : body) Instantiate(*s, scope, out);
}

namespace {

// Tags an exception from statement `s` with the file `s` is written in,
// unless a place deeper down already did.
template <typename Error>
void TagFile(Error& e, const Stmt& s) {
  if (e.file.empty() && s.file) e.file = *s.file;
}

}  // namespace

void Evaluator::Define(const std::vector<StmtPtr>& body, Scope& scope) {
  for (const StmtPtr& s : body) {
    if (s->kind == Stmt::Kind::kModuleDef)
      scope.modules[s->name] = s->module;
    else if (s->kind == Stmt::Kind::kFunctionDef)
      scope.functions[s->name] = s->function;
  }
  for (const StmtPtr& s : body) {
    if (s->kind != Stmt::Kind::kAssign) continue;
    try {
      // A module body's assignment to one of its parameters (MCAD's gear()
      // does `circular_pitch = (circular_pitch != false ? ...)`) reads the
      // argument and replaces it, as in OpenSCAD (the parser already merged
      // assignments repeated in one scope, parser.cc).
      scope.vars[s->name] = Eval(*s->expr, scope);
    } catch (NotNative& e) {
      TagFile(e, *s);
      throw;
    } catch (BadModel& e) {
      TagFile(e, *s);
      throw;
    }
  }
}

std::vector<CsgOut> Evaluator::Children(const Stmt& s, const Scope& call) {
  std::vector<CsgOut> out;
  Scope inner;
  inner.lexical = inner.dynamic = &call;
  Run(s.children, inner, out);
  return out;
}

// The nodes of one statement appended to out.
void Evaluator::Instantiate(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
  try {
    InstantiateHere(s, scope, out);
  } catch (NotNative& e) {
    TagFile(e, s);
    throw;
  } catch (BadModel& e) {
    TagFile(e, s);
    throw;
  }
}

void Evaluator::InstantiateHere(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
  Guard(s.line);
  if (!s.modifier.empty()) {
    Modified(s, scope, out);
    return;
  }
  switch (s.kind) {
    case Stmt::Kind::kAssign:
    case Stmt::Kind::kModuleDef:
    case Stmt::Kind::kFunctionDef:
    case Stmt::Kind::kDisabled:
      return;
    case Stmt::Kind::kBlock:
      Block(s, scope, out);
      return;
    case Stmt::Kind::kIf:
      If(s, scope, out);
      return;
    case Stmt::Kind::kFor:
      For(s, scope, out);
      return;
    case Stmt::Kind::kIntersectionFor:
      IntersectionFor(s, scope, out);
      return;
    case Stmt::Kind::kLet:
      Let(s, scope, out);
      return;
    case Stmt::Kind::kCall:
      CallModule(s, scope, out);
      return;
  }
}

// `#` or `%` before a statement that makes at most one node. Before
// `child()` or `children()` OpenSCAD 2021.01 drops it: the children keep
// their own (testing-data's child-background.scad, whose `%child()` cylinder
// its export and render still subtract).
void Evaluator::Modified(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
  Stmt plain = s;
  plain.modifier.clear();
  if (s.kind == Stmt::Kind::kCall && (s.name == "child" || s.name == "children")) {
    Instantiate(plain, scope, out);
    return;
  }
  const std::size_t before = out.size();
  Instantiate(plain, scope, out);
  if (out.size() > before + 1) throw NotNative{s.line, "modifier '" + s.modifier + "' on several nodes"};
  if (out.size() == before + 1) out.back().modifier = s.modifier;
}

// A bare `{ }` block: its statements in the enclosing scope.
void Evaluator::Block(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
  for (const StmtPtr& c : s.children) {
    if (c->kind == Stmt::Kind::kAssign || c->kind == Stmt::Kind::kModuleDef || c->kind == Stmt::Kind::kFunctionDef)
      throw NotNative{c->line, "a definition inside a bare { } block"};
    Instantiate(*c, scope, out);
  }
}

void Evaluator::If(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
  const bool then = Eval(*s.expr, scope).Truthy();
  if (!then && s.otherwise.empty()) return;
  CsgOut group{"group()", {}};
  Scope inner;
  inner.lexical = inner.dynamic = &scope;
  Run(then ? s.children : s.otherwise, inner, group.children);
  out.push_back(std::move(group));
}

void Evaluator::For(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
  CsgOut group{"group()", {}};
  Loop(s.bindings, 0, scope, [&](const Scope& bound) {
    Scope inner;
    inner.lexical = inner.dynamic = &bound;
    Run(s.children, inner, group.children);
  });
  out.push_back(std::move(group));
}

// OpenSCAD exports intersection() of every iteration's nodes side by side,
// which is the intersection only when each iteration makes one node (its
// render intersects each iteration's union): declined otherwise.
void Evaluator::IntersectionFor(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
  CsgOut both{"intersection()", {}};
  Loop(s.bindings, 0, scope, [&](const Scope& bound) {
    Scope inner;
    inner.lexical = inner.dynamic = &bound;
    const std::size_t before = both.children.size();
    Run(s.children, inner, both.children);
    if (both.children.size() != before + 1)
      throw NotNative{s.line, "intersection_for with an iteration making other than one node"};
  });
  out.push_back(std::move(both));
}

void Evaluator::Let(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
  CsgOut group{"group()", {}};
  Scope bound;
  bound.lexical = bound.dynamic = &scope;
  Bind(s.bindings, bound);
  Scope inner;
  inner.lexical = inner.dynamic = &bound;
  Run(s.children, inner, group.children);
  out.push_back(std::move(group));
}

// assign(a = x, b = y) children: the named arguments, each evaluated in the
// caller's scope (not seeing each other, unlike let), bound for the children,
// which become a group().
void Evaluator::Assign(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
  Scope bound;
  bound.lexical = bound.dynamic = &scope;
  for (const Binding& b : s.bindings)
    if (!b.name.empty()) bound.vars[b.name] = Eval(*b.expr, scope);
  CsgOut group{"group()", {}};
  Scope inner;
  inner.lexical = inner.dynamic = &bound;
  Run(s.children, inner, group.children);
  out.push_back(std::move(group));
}

namespace {

// Whether a child statement counts for $children and children(i) (OpenSCAD
// counts module instantiations, not assignments or definitions).
std::size_t Instantiates(const Stmt& s) {
  return s.kind == Stmt::Kind::kCall || s.kind == Stmt::Kind::kIf || s.kind == Stmt::Kind::kFor ||
                 s.kind == Stmt::Kind::kIntersectionFor || s.kind == Stmt::Kind::kLet || s.kind == Stmt::Kind::kBlock
             ? 1
             : 0;
}

}  // namespace

// A module instantiation: echo, children, a user module, assert, or a
// built-in module.
void Evaluator::CallModule(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
  if (s.name == "echo") {
    if (!s.children.empty()) {
      Scope call;
      call.lexical = call.dynamic = &scope;
      out.push_back({"group()", Children(s, call)});
    }
    return;
  }
  Definition where;
  const std::shared_ptr<const ModuleDef> m = s.name == "children" ? nullptr : FindModule(s.name, scope, &where);
  if (s.name == "children" || (s.name == "child" && !m)) {
    ChildrenCall(s, scope, out);
    return;
  }
  if (m) {
    UserModule(s, *m, where, scope, out);
    return;
  }
  Scope call;
  call.lexical = call.dynamic = &scope;
  if (s.name == "assign") {  // deprecated, evaluated by OpenSCAD 2021.01 (MCAD's involute_gears.scad)
    Assign(s, scope, out);
    return;
  }
  if (s.name == "assert") {
    std::map<std::string, Value> specials;
    auto args = Match(s.bindings, {"condition", "message"}, scope, s.line, &specials);
    if (!args["condition"].Truthy()) throw NotNative{s.line, "a failed assert"};
    if (!s.children.empty()) out.push_back({"group()", Children(s, call)});
    return;
  }
  CallBuiltinModule(*this, s, scope, call, out);
}

// A user module's body as a group(), its parameters bound and its children
// kept for children().
void Evaluator::UserModule(const Stmt& s, const ModuleDef& m, const Definition& where, Scope& scope,
                           std::vector<CsgOut>& out) {
  if (++depth_ > 10000) throw NotNative{s.line, "recursion deeper than 10,000 calls"};
  std::vector<std::unique_ptr<Scope>> hold;
  Scope body;
  CallScopes(where, scope, body, hold);
  body.module_body = true;
  body.children = &s.children;
  body.children_scope = &scope;
  BindParameters(m.params, s.bindings, scope, body, s.line);
  std::size_t count = 0;
  for (const StmtPtr& c : s.children) count += Instantiates(*c);
  body.vars["$children"] = Value::Number(static_cast<double>(count));
  CsgOut group{"group()", {}};
  Run(m.body, body, group.children);
  out.push_back(std::move(group));
  --depth_;
}

// children() (all, as a group()) or children(i) of the module body the
// call is in; nothing at top level. child() and child(i), deprecated in
// OpenSCAD 2021.01 but still evaluated by it (MCAD's involute_gears.scad
// calls child(0)), are children(0) and children(i).
void Evaluator::ChildrenCall(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
  const Scope* body = scope.Body();
  if (!body) return;  // top level: no children
  if (!s.children.empty()) throw NotNative{s.line, "children() with children"};
  std::vector<const Stmt*> instantiations;
  for (const StmtPtr& c : *body->children) {
    if (c->kind == Stmt::Kind::kBlock) throw NotNative{c->line, "a { } block among a module's children"};
    if (Instantiates(*c)) instantiations.push_back(c.get());
  }
  // The children run where they were written, with the $-variables of the
  // place children() is called.
  Scope written;
  written.lexical = body->children_scope;
  written.dynamic = &scope;
  Define(*body->children, written);
  if (s.bindings.empty() && s.name == "children") {
    CsgOut group{"group()", {}};
    for (const Stmt* c : instantiations) Instantiate(*c, written, group.children);
    out.push_back(std::move(group));
    return;
  }
  if (s.bindings.size() > 1 || (s.bindings.size() == 1 && !s.bindings[0].name.empty()))
    throw NotNative{s.line, s.name + "() with these arguments"};
  const Value i = s.bindings.empty() ? Value::Number(0) : Eval(*s.bindings[0].expr, scope);
  if (!i.IsNumber()) throw NotNative{s.line, s.name + "() of a vector or range"};
  const double k = std::floor(i.number);
  if (!(k >= 0 && k < static_cast<double>(instantiations.size()))) return;
  Instantiate(*instantiations[static_cast<std::size_t>(k)], written, out);
}

}  // namespace fabatlas::scad::internal
