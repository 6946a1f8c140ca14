// evaluate_model/syntax.h (internal to fabatlas_scad) — the syntax tree of an
// OpenSCAD model as evaluate_model.h's evaluator reads it (OpenSCAD User
// Manual, "The OpenSCAD Language"), and NotNative, how every part of the
// evaluator declines.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "fabatlas/scad/lex_source.h"

namespace fabatlas::scad::internal {

// Thrown for anything the evaluator does not implement; the caller asks
// OpenSCAD instead. `line` is the source line (0: none) in `file` (empty: the
// model itself; else an included or used file).
struct NotNative {
  int line;
  std::string what;
  std::string file = {};
};

// The model is wrong whatever evaluates it (an unknown colour name): bad
// input, reported to the user (ModelEvaluation::bad_input), not declined.
struct BadModel {
  int line;
  std::string what;
  std::string file = {};  // as NotNative's
};

using Token = SourceToken;
using Tok = SourceToken::Kind;

struct Expr;
using ExprPtr = std::shared_ptr<const Expr>;

struct Binding {  // `name = expr` in argument lists, let, for; positional when name is empty
  std::string name;
  ExprPtr expr;
};

struct Expr {
  enum class Kind {
    kNumber,
    kString,
    kBool,
    kUndef,
    kIdent,
    kVector,
    kRange,
    kUnary,
    kBinary,
    kTernary,
    kCall,
    kIndex,
    kMember,
    kLet,
    kEcho,
    kAssert,
    // list comprehension elements (only inside kVector items)
    kCompFor,
    kCompIf,
    kCompLet,
    kEach
  } kind;
  int line = 0;
  double number = 0;
  bool boolean = false;
  std::string text;               // identifier, string, operator, member or callee name
  std::vector<ExprPtr> items;     // vector items; range begin, step, end; operands
  std::vector<Binding> bindings;  // call arguments, let / for bindings
};

// A new expression node of `kind` read at source line `line`.
inline std::shared_ptr<Expr> NewExpr(Expr::Kind kind, int line) {
  auto e = std::make_shared<Expr>();
  e->kind = kind;
  e->line = line;
  return e;
}

struct Stmt;
using StmtPtr = std::shared_ptr<const Stmt>;

struct ModuleDef {
  std::vector<Binding> params;  // defaults in expr (null when none)
  std::vector<StmtPtr> body;
};

struct FunctionDef {
  std::vector<Binding> params;
  ExprPtr body;
  std::shared_ptr<const std::string> file;  // the file it is written in (messages)
};

struct Stmt {
  enum class Kind {
    kAssign,
    kCall,
    kBlock,
    kIf,
    kFor,
    kIntersectionFor,
    kLet,
    kModuleDef,
    kFunctionDef,
    kDisabled
  } kind;
  int line = 0;
  std::string name;                // assigned variable, called or defined module/function
  std::string modifier;            // a call's "%" or "#"
  ExprPtr expr;                    // assigned value, if condition
  std::vector<Binding> bindings;   // call arguments, for / let bindings
  std::vector<StmtPtr> children;   // call's children, block's statements, if's then-branch
  std::vector<StmtPtr> otherwise;  // if's else-branch
  std::shared_ptr<const ModuleDef> module;
  std::shared_ptr<const FunctionDef> function;
  std::shared_ptr<const std::string> file;  // the file it is written in (messages); null: -D
};

}  // namespace fabatlas::scad::internal
