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
#include <string>
#include <vector>

#include "csg_node.h"
#include "scope.h"
#include "syntax.h"
#include "value.h"

namespace fabatlas::scad::internal {

// The stack the evaluation may use: deep recursion in a model declines (and
// OpenSCAD evaluates it) well before the smallest thread stack fabatlas runs
// samples on (TBB's 4 MiB); about 2 KiB per level of a recursive function
// or module.
constexpr std::ptrdiff_t kStackBudget = 1024 * 1024;

class Evaluator {
 public:
  Evaluator() : stack_base_(reinterpret_cast<std::uintptr_t>(__builtin_frame_address(0))) {}

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
  const Scope* DefinitionScope(const std::string& name, const Scope& scope, bool module);
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
  void Modified(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void Block(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void If(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void For(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void IntersectionFor(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void Let(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void CallModule(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);
  void UserModule(const Stmt& s, const ModuleDef& m, Scope& scope, std::vector<CsgOut>& out);
  void ChildrenCall(const Stmt& s, Scope& scope, std::vector<CsgOut>& out);

  int depth_ = 0;
  long iterations_ = 0;
  long steps_ = 0;
  std::uintptr_t stack_base_;
};

}  // namespace fabatlas::scad::internal
