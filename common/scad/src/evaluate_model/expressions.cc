// Expressions of evaluate_model.h's evaluator (evaluator.h): names,
// ranges, vectors and list comprehensions, operators, indexing, let, and
// calls of user functions (built-in ones: builtin_functions.h).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <type_traits>

#include "builtin_functions.h"
#include "evaluator.h"

namespace fabatlas::scad::internal {

Value Evaluator::Eval(const Expr& e, const Scope& scope) {
  Guard(e.line);
  switch (e.kind) {
    case Expr::Kind::kNumber:
      return Value::Number(e.number);
    case Expr::Kind::kString:
      return Value::String(e.text);
    case Expr::Kind::kBool:
      return Value::Bool(e.boolean);
    case Expr::Kind::kUndef:
      return Value();
    case Expr::Kind::kIdent:
      return Identifier(e, scope);
    case Expr::Kind::kRange:
      return Range(e, scope);
    case Expr::Kind::kVector: {
      std::vector<Value> items;
      for (const ExprPtr& item : e.items) Element(*item, scope, items);
      return Value::Vector(std::move(items));
    }
    case Expr::Kind::kUnary:
      return UnaryOp(e, scope);
    case Expr::Kind::kBinary:
      return BinaryOp(e, scope);
    case Expr::Kind::kTernary:
      return Eval(*e.items[0], scope).Truthy() ? Eval(*e.items[1], scope) : Eval(*e.items[2], scope);
    case Expr::Kind::kIndex:
      return Index(e, scope);
    case Expr::Kind::kMember:
      return Member(e, scope);
    case Expr::Kind::kLet:
      return LetExpression(e, scope);
    case Expr::Kind::kCall:
      return Call(e, scope);
    case Expr::Kind::kEcho:
      return Eval(*e.items[0], scope);
    case Expr::Kind::kAssert:
      if (e.bindings.empty() || !Eval(*e.bindings[0].expr, scope).Truthy()) throw NotNative{e.line, "a failed assert"};
      return Eval(*e.items[0], scope);
    default:
      throw NotNative{e.line, "a list comprehension element outside [ ]"};
  }
}

Value Evaluator::Identifier(const Expr& e, const Scope& scope) {
  const Value* v = scope.Find(e.text);
  if (!v) {
    if (e.text == "PI") return Value::Number(std::numbers::pi);
    throw NotNative{e.line, "unknown variable '" + e.text + "'"};
  }
  return *v;
}

// `[begin : end]` or `[begin : step : end]`.
Value Evaluator::Range(const Expr& e, const Scope& scope) {
  Value r;
  r.kind = Value::Kind::kRange;
  const Value b = Eval(*e.items[0], scope), en = Eval(*e.items[2], scope);
  const Value st = e.items[1] ? Eval(*e.items[1], scope) : Value::Number(1);
  if (!b.IsNumber() || !en.IsNumber() || !st.IsNumber()) throw NotNative{e.line, "a range of non-numbers"};
  r.range[0] = b.number;
  r.range[1] = st.number;
  r.range[2] = en.number;
  if (!e.items[1] && b.number > en.number) std::swap(r.range[0], r.range[2]);  // deprecated [a:b], a > b
  return r;
}

Value Evaluator::UnaryOp(const Expr& e, const Scope& scope) {
  const Value a = Eval(*e.items[0], scope);
  if (e.text == "!") return Value::Bool(!a.Truthy());
  if (e.text == "+") {
    if (!a.IsNumber() && !a.IsVector()) throw NotNative{e.line, "unary + of a non-number"};
    return a;
  }
  return Negate(a, e.line);
}

Value Evaluator::BinaryOp(const Expr& e, const Scope& scope) {
  const std::string& op = e.text;
  if (op == "&&") return Value::Bool(Eval(*e.items[0], scope).Truthy() && Eval(*e.items[1], scope).Truthy());
  if (op == "||") return Value::Bool(Eval(*e.items[0], scope).Truthy() || Eval(*e.items[1], scope).Truthy());
  const Value a = Eval(*e.items[0], scope), b = Eval(*e.items[1], scope);
  if (op == "==") return Value::Bool(Equal(a, b));
  if (op == "!=") return Value::Bool(!Equal(a, b));
  if (op == "<" || op == ">" || op == "<=" || op == ">=") {
    if (!a.IsNumber() || !b.IsNumber()) throw NotNative{e.line, "comparison of non-numbers"};
    const double x = a.number, y = b.number;
    return Value::Bool(op == "<" ? x < y : op == ">" ? x > y : op == "<=" ? x <= y : x >= y);
  }
  return Arithmetic(op, a, b, e.line);
}

// `a[i]` of a vector or string; undef outside it.
Value Evaluator::Index(const Expr& e, const Scope& scope) {
  const Value a = Eval(*e.items[0], scope), i = Eval(*e.items[1], scope);
  if (!i.IsNumber()) throw NotNative{e.line, "an index that is not a number"};
  if (a.IsVector()) {
    const double k = std::floor(i.number);
    if (!(k >= 0 && k < static_cast<double>(a.Items().size()))) return Value();
    return a.Items()[static_cast<std::size_t>(k)];
  }
  if (a.kind == Value::Kind::kString) {
    const double k = std::floor(i.number);
    if (!(k >= 0 && k < static_cast<double>(a.text.size()))) return Value();
    return Value::String(std::string(1, a.text[static_cast<std::size_t>(k)]));
  }
  throw NotNative{e.line, "indexing a value that is not a vector or string"};
}

// `v.x`, `v.y`, `v.z`.
Value Evaluator::Member(const Expr& e, const Scope& scope) {
  const Value a = Eval(*e.items[0], scope);
  const std::size_t k = e.text == "x" ? 0 : e.text == "y" ? 1 : e.text == "z" ? 2 : 3;
  if (!a.IsVector() || k == 3) throw NotNative{e.line, "member '." + e.text + "'"};
  return k < a.Items().size() ? a.Items()[k] : Value();
}

Value Evaluator::LetExpression(const Expr& e, const Scope& scope) {
  Scope inner;
  inner.lexical = inner.dynamic = &scope;
  Bind(e.bindings, inner);
  return Eval(*e.items[0], inner);
}

// let / for bindings evaluated in order, each seeing the ones before it.
void Evaluator::Bind(const std::vector<Binding>& bindings, Scope& inner) {
  for (const Binding& b : bindings) {
    if (b.name.empty()) throw NotNative{b.expr->line, "a let without a name"};
    inner.vars[b.name] = Eval(*b.expr, inner);
  }
}

// The values a for runs through: a range's, a vector's items, or a number
// or boolean itself.
std::vector<Value> Evaluator::Iterate(const Value& v, int line) {
  if (v.kind == Value::Kind::kRange) {
    std::vector<Value> out;
    for (double x : RangeValues(v, line)) out.push_back(Value::Number(x));
    return out;
  }
  if (v.IsVector()) return v.Items();
  if (v.IsNumber() || v.kind == Value::Kind::kBool) return {v};
  throw NotNative{line, "a loop over a string or undef"};
}

// A vector item or list comprehension element, appended to out.
void Evaluator::Element(const Expr& e, const Scope& scope, std::vector<Value>& out) {
  switch (e.kind) {
    case Expr::Kind::kCompFor:
      Loop(e.bindings, 0, scope, [&](const Scope& inner) { Element(*e.items[0], inner, out); });
      return;
    case Expr::Kind::kCompLet: {
      Scope inner;
      inner.lexical = inner.dynamic = &scope;
      Bind(e.bindings, inner);
      Element(*e.items[0], inner, out);
      return;
    }
    case Expr::Kind::kCompIf:
      if (Eval(*e.items[0], scope).Truthy())
        Element(*e.items[1], scope, out);
      else if (e.items.size() > 2)
        Element(*e.items[2], scope, out);
      return;
    case Expr::Kind::kEach: {
      const Value v = Eval(*e.items[0], scope);
      if (v.IsVector() || v.kind == Value::Kind::kRange) {
        for (const Value& x : Iterate(v, e.line)) out.push_back(x);
      } else {
        throw NotNative{e.line, "each of a non-vector"};
      }
      return;
    }
    default:
      out.push_back(Eval(e, scope));
  }
}

std::map<std::string, Value> Evaluator::Match(const std::vector<Binding>& args, const std::vector<std::string>& names,
                                              const Scope& scope, int line, std::map<std::string, Value>* specials) {
  std::map<std::string, Value> out;
  std::size_t position = 0;
  for (const Binding& a : args) {
    if (a.name.empty()) {
      if (position >= names.size()) throw NotNative{line, "too many positional arguments"};
      out[names[position++]] = Eval(*a.expr, scope);
    } else if (a.name[0] == '$' && specials) {
      (*specials)[a.name] = Eval(*a.expr, scope);
    } else {
      if (std::find(names.begin(), names.end(), a.name) == names.end())
        throw NotNative{line, "argument '" + a.name + "' not known here"};
      out[a.name] = Eval(*a.expr, scope);
    }
  }
  return out;
}

// A user function or a built-in one.
Value Evaluator::Call(const Expr& e, const Scope& scope) {
  Definition where;
  if (auto f = FindFunction(e.text, scope, &where)) {
    if (++depth_ > 10000) throw NotNative{e.line, "recursion deeper than 10,000 calls"};
    std::vector<std::unique_ptr<Scope>> hold;
    Scope inner;
    CallScopes(where, scope, inner, hold);
    BindParameters(f->params, e.bindings, scope, inner, e.line);
    Value v;
    try {
      v = Eval(*f->body, inner);
    } catch (NotNative& x) {
      if (x.file.empty() && f->file) x.file = *f->file;
      throw;
    } catch (BadModel& x) {
      if (x.file.empty() && f->file) x.file = *f->file;
      throw;
    }
    --depth_;
    return v;
  }
  std::vector<Value> a;
  for (const Binding& b : e.bindings) {
    if (!b.name.empty()) throw NotNative{e.line, "named argument to built-in function " + e.text};
    a.push_back(Eval(*b.expr, scope));
  }
  return CallBuiltinFunction(e.text, a, e.line);
}

namespace {

template <typename Def>
std::shared_ptr<const Def> Own(const Scope& s, const std::string& name) {
  if constexpr (std::is_same_v<Def, ModuleDef>) {
    auto it = s.modules.find(name);
    return it == s.modules.end() ? nullptr : it->second;
  } else {
    auto it = s.functions.find(name);
    return it == s.functions.end() ? nullptr : it->second;
  }
}

template <typename Def>
std::shared_ptr<const Def> Own(const SourceFile& f, const std::string& name) {
  if constexpr (std::is_same_v<Def, ModuleDef>) {
    auto it = f.modules.find(name);
    return it == f.modules.end() ? nullptr : it->second;
  } else {
    auto it = f.functions.find(name);
    return it == f.functions.end() ? nullptr : it->second;
  }
}

}  // namespace

const SourceFile* Evaluator::Used(const std::string& path) {
  auto it = used_files_.find(path);
  if (it == used_files_.end()) it = used_files_.emplace(path, UsedFile(path)).first;
  return it->second.get();
}

template <typename Def>
std::shared_ptr<const Def> Evaluator::Find(const std::string& name, const Scope& scope, Definition* where) {
  for (const Scope* s = &scope; s; s = s->lexical) {
    if (auto d = Own<Def>(*s, name)) {
      if (where) *where = {s, nullptr};
      return d;
    }
    if (s->uses)
      for (const std::string& path : *s->uses) {
        const SourceFile* used = Used(path);
        if (auto d = Own<Def>(*used, name)) {
          if (where) *where = {nullptr, used};
          return d;
        }
      }
  }
  return nullptr;
}

std::shared_ptr<const ModuleDef> Evaluator::FindModule(const std::string& name, const Scope& scope, Definition* where) {
  return Find<ModuleDef>(name, scope, where);
}

std::shared_ptr<const FunctionDef> Evaluator::FindFunction(const std::string& name, const Scope& scope,
                                                           Definition* where) {
  return Find<FunctionDef>(name, scope, where);
}

void Evaluator::CallScopes(const Definition& where, const Scope& caller, Scope& inner,
                           std::vector<std::unique_ptr<Scope>>& hold) {
  inner.dynamic = &caller;
  if (!where.used) {
    inner.lexical = where.scope;
    return;
  }
  const SourceFile* used = where.used;
  // The used file's top-level scope under `dynamic` (null: no $-variable
  // but its own can be read).
  auto make = [&](const Scope* dynamic) {
    if (!used_building_.insert(used).second)
      throw NotNative{0, "its top-level assignments call into themselves through another file", used->path};
    auto top = std::make_unique<Scope>();
    top->lexical = builtins_;
    top->dynamic = dynamic;
    top->uses = &used->uses;
    const int depth = depth_;
    try {
      std::vector<StmtPtr> statements = used->statements;
      for (const auto& [name, value] : overrides_) Override(statements, name, value);
      Define(statements, *top);
    } catch (...) {
      used_building_.erase(used);
      depth_ = depth;
      throw;
    }
    used_building_.erase(used);
    return top;
  };
  if (!used_scopes_.count(used) && !used_dynamic_.count(used)) {
    try {
      used_scopes_[used] = make(nullptr);
    } catch (const NotNative&) {
      used_dynamic_.insert(used);  // reads the caller's $-variables (or declines again below)
    }
  }
  if (used_dynamic_.count(used)) {
    hold.push_back(make(&caller));
    inner.lexical = inner.dynamic = hold.back().get();
    return;
  }
  const Scope* top = used_scopes_[used].get();
  inner.lexical = top;
  auto shim = std::make_unique<Scope>();  // the file's own $-variables above the caller's
  for (const auto& [name, value] : top->vars)
    if (name[0] == '$') shim->vars[name] = value;
  if (shim->vars.empty()) return;
  shim->dynamic = &caller;
  inner.dynamic = shim.get();
  hold.push_back(std::move(shim));
}

// A user function's or module's parameters bound in `inner`: the arguments
// (evaluated in the caller's scope), else the defaults (evaluated in inner),
// else undef; $-arguments become inner's $-variables.
void Evaluator::BindParameters(const std::vector<Binding>& params, const std::vector<Binding>& args,
                               const Scope& caller, Scope& inner, int line) {
  std::size_t position = 0;
  std::map<std::string, Value> given;
  for (const Binding& a : args) {
    if (a.name.empty()) {
      if (position >= params.size()) throw NotNative{line, "too many positional arguments"};
      given[params[position++].name] = Eval(*a.expr, caller);
    } else if (a.name[0] == '$') {
      inner.vars[a.name] = Eval(*a.expr, caller);
    } else {
      bool known = false;
      for (const Binding& p : params) known = known || p.name == a.name;
      if (!known) throw NotNative{line, "argument '" + a.name + "' not a parameter"};
      given[a.name] = Eval(*a.expr, caller);
    }
  }
  for (const Binding& p : params) {
    auto it = given.find(p.name);
    if (it != given.end())
      inner.vars[p.name] = it->second;
    else if (p.expr)
      inner.vars[p.name] = Eval(*p.expr, inner);
    else
      inner.vars[p.name] = Value();
  }
}

}  // namespace fabatlas::scad::internal
