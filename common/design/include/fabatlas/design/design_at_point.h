// fabatlas/design/design_at_point.h — a design file whose defaults are a
// given point: the file's own text (comments and layout kept) with each
// exposed parameter's `default:` set to its value at u (inserted in a flow
// map that has none). `fabatlas resolve -o` writes the resolved design so.
#pragma once

#include <string>

#include "fabatlas/design/design.h"

namespace fabatlas::design {

// Throws InputError when a parameter's default cannot be found or placed
// (a block-style spec without `default:`), or when the text it produces
// does not load back with u as its default point.
std::string DesignTextAt(const Design& design, const Point& u);

}  // namespace fabatlas::design
