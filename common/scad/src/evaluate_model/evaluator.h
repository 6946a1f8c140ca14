// evaluate_model/evaluator.h (internal to fabatlas_scad) — the evaluator of
// evaluate_model.h: a model's statements run to a CSG tree
// (statements.cc) and its expressions to values
// (expressions.cc), with OpenSCAD's scoping rules; built-in functions
// and modules live in builtin_functions.h and builtin_modules.h.
// One Evaluator per model and thread; it bounds the work, loops, recursion
// and stack a model may use and declines with NotNative past them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "csg_node.h"
#include "scope.h"
#include "source_files.h"
#include "syntax.h"
#include "value.h"

namespace fabatlas::scad::internal {

// The stack the evaluation may use: deep recursion in a model declines (and
// OpenSCAD evaluates it) well before the smallest thread stack fabatlas runs
// samples on (TBB's 4 MiB); about 2 KiB per level of a recursive function
// or module.
constexpr std::ptrdiff_t kStackBudget = 1024 * 1024;

// -D name=value (OpenSCAD's command line) applied to a file's top-level
// statements: the value replaces the assignment of `name` at its place, or
// is assigned after the last statement. OpenSCAD 2021.01 applies it so to the
// model and to every file it uses (`-D v=1` changes a used file's `v = 3`,
// and a used file's modules see `-D zz=5` though it assigns no zz).
void Override(std::vector<StmtPtr>& program, const std::string& name, const ExprPtr& value);

// Where a module or function is defined, as seen from a scope: a scope
// along the lexical chain, or a used file (its top-level scope is made for
// the call, evaluator.h's CallScopes).
struct Definition {
  const Scope* scope = nullptr;
  const SourceFile* used = nullptr;
};

class Evaluator {
 public:
  // `builtins`: the scope above every file's (the special variables'
  // defaults); a used file's top-level scope hangs below it.
  // `overrides`: the -D values (Override), applied to the used files too.
  Evaluator(const Scope* builtins, std::vector<std::pair<std::string, ExprPtr>> overrides)
      : builtins_(builtins),
        overrides_(std::move(overrides)),
        stack_base_(reinterpret_cast<std::uintptr_t>(__builtin_frame_address(0))) {}

  // Called at every expression and statement: bounds the stack and the work
  // (20 million steps, a second or two; exponential recursion such as
  // f(n - 1) + f(n - 1) declines instead of running for hours).
  void Guard(int line) {
    if (++steps_ > 20'000'000) throw NotNative{line, "more than 20 million evaluation steps"};
    const auto here = reinterpret_cast<std::uintptr_t>(__builtin_frame_address(0));
    if (stack_base_ > here && static_cast<std::ptrdiff_t>(stack_base_ - here) > kStackBudget)
      throw NotNative{line, "recursion deeper than the evaluator's stack budget"};
  }

  // The statements of one scope: definitions first, then the assignments in
  // order, then the instantiations in order (OpenSCAD's rule).
  void Run(const std::vector<StmtPtr>& body, Scope& scope, std::vector<CsgOut>& out);
  // The definitions and assignments of `body` into scope.
  void Define(const std::vector<StmtPtr>& body, Scope& scope);
  // The value of e in scope.
  Value Eval(const Expr& e, const Scope& scope);

  // Arguments matched to parameter names as OpenSCAD matches them: positional
  // in order, then by name; $-arguments go to *specials when given.
  std::map<std::string, Value> Match(const std::vector<Binding>& args, const std::vector<std::string>& names,
                                     const Scope& scope, int line, std::map<std::string, Value>* specials = nullptr);
  // The child statements of a built-in module instantiation, in a scope of
  // their own under `call` (which holds the instantiation's $-arguments).
  std::vector<CsgOut> Children(const Stmt& s, const Scope& call);

 private:
  // Expressions (expressions.cc).
  Value Identifier(const Expr& e, const Scope& scope);
  Value Range(const Expr& e, const Scope& scope);
  Value UnaryOp(const Expr& e, const Scope& scope);
  Value BinaryOp(const Expr& e, const Scope& scope);
  Value Index(const Expr& e, const Scope& scope);
  Value Member(const Expr& e, const Scope& scope);
  Value LetExpression(const Expr& e, const Scope& scope);
  void Bind(const std::vector<Binding>& bindings, Scope& inner);
  std::vector<Value> Iterate(const Value& v, int line);
  void Element(const Expr& e, const Scope& scope, std::vector<Value>& out);
  Value Call(const Expr& e, const Scope& scope);
  // The module (module true) or function `name` seen from `scope`: along
  // the lexical chain each scope's own, and at a file's scope after its own
  // those of the files it uses, in the order used; null when none.
  std::shared_ptr<const ModuleDef> FindModule(const std::string& name, const Scope& scope, Definition* where);
  std::shared_ptr<const FunctionDef> FindFunction(const std::string& name, const Scope& scope, Definition* where);
  const SourceFile* Used(const std::string& path);
  // FindModule and FindFunction: Def is ModuleDef or FunctionDef.
  template <typename Def>
  std::shared_ptr<const Def> Find(const std::string& name, const Scope& scope, Definition* where);
  // The lexical and dynamic parents of a call's scope `inner` for a
  // definition found at `where`, called from `caller`. A used file's
  // definitions see its top-level assignments, evaluated as OpenSCAD
  // evaluates them at each call (under the caller's $-variables; done once
  // and kept when they read none), and its top-level $-variables shadow the
  // caller's. `hold` keeps what is made for the call alive.
  void CallScopes(const Definition& where, const Scope& caller, Scope& inner,
                  std::vector<std::unique_ptr<Scope>>& hold);
  void BindParameters(const std::vector<Binding>& params, const std::vector<Binding>& args, const Scope& caller,
                      Scope& inner, int line);

  // Nested loops over `bindings` (for (a = ..., b = ...)), calling `body` with
  // the scope of each combination.
  template <typename Body>
  void Loop(const std::vector<Binding>& bindings, std::size_t k, const Scope& outer, Body&& body) {
    if (k == bindings.size()) {
      body(outer);
      return;
    }
    const Binding& b = bindings[k];
    if (b.name.empty()) throw NotNative{b.expr->line, "a C-style or unnamed for"};
    for (const Value& v : Iterate(Eval(*b.expr, outer), b.expr->line)) {
      if (++iterations_ > 1000000) throw NotNative{b.expr->line, "more than 1,000,000 loop iterations"};
      Scope inner;
      inner.lexical = inner.dynamic = &outer;
      inner.vars[b.name] = v;
      Loop(bindings, k + 1, inner, body);
    }
  }

  // Statements (statements.cc).
  void Instantiate(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void InstantiateHere(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void Modified(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void Block(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void If(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void For(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void IntersectionFor(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void Let(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void Assign(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void CallModule(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void UserModule(const Stmt& s, const ModuleDef& m, const Definition& where, Scope& scope, std::vector<CsgOut>& out);
  void ChildrenCall(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);

  const Scope* builtins_;
  std::vector<std::pair<std::string, ExprPtr>> overrides_;
  std::map<std::string, std::shared_ptr<const SourceFile>> used_files_;
  std::map<const SourceFile*, std::unique_ptr<Scope>> used_scopes_;  // top-level scopes reading no $-variable
  std::set<const SourceFile*> used_dynamic_;                         // top-level scopes made per call
  std::set<const SourceFile*> used_building_;
  int depth_ = 0;
  long iterations_ = 0;
  long steps_ = 0;
  std::uintptr_t stack_base_;
};

}  // namespace fabatlas::scad::internal
