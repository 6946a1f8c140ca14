// evaluate_model/builtin_modules.h (internal to fabatlas_scad) — OpenSCAD 2021.01's
// built-in modules that evaluate_model.h implements (its header lists
// them), one small function each, found by name in a table; each writes
// its node as OpenSCAD's .csg export does.
#pragma once

#include <vector>

#include "csg_node.h"
#include "evaluator.h"
#include "scope.h"
#include "syntax.h"

namespace fabatlas::scad::internal {

// The instantiation s of a built-in module, written in `scope`: its node
// appended to out. `call` is the scope of its children and receives its
// $-arguments. Declines "module NAME()" for a module not in the table, and
// what each module says for arguments it does not take.
void CallBuiltinModule(Evaluator& evaluator, const Stmt& s, const Scope& scope, Scope& call, std::vector<CsgOut>& out);

}  // namespace fabatlas::scad::internal
