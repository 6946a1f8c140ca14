// evaluate_model/builtin_functions.h (internal to fabatlas_scad) — OpenSCAD 2021.01's
// built-in functions that evaluate_model.h implements (its header lists
// them), one small function each, found by name in a table.
#pragma once

#include <string>
#include <vector>

#include "value.h"

namespace fabatlas::scad::internal {

// Built-in function `name` of positional arguments `args`, called at source
// line `line`. Declines "function NAME() with these arguments" for a name
// not in the table or arguments the function does not take, and what each
// function says for arguments of the wrong type.
Value CallBuiltinFunction(const std::string& name, const std::vector<Value>& args, int line);

}  // namespace fabatlas::scad::internal
