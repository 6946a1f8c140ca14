// fabatlas/scad/evaluate_model.h — a Customizer model's evaluated CSG tree
// computed by fabatlas itself, without starting OpenSCAD: the text OpenSCAD
// 2021.01's `openscad -o model.csg -D name=value ... model.scad` writes, for
// the language subset such models use. Whatever the evaluator does not
// implement makes it decline (never guess), and the caller asks OpenSCAD.
//
// The subset (OpenSCAD User Manual, "The OpenSCAD Language"):
//  - assignments (evaluated before the instantiations of their scope, as
//    OpenSCAD does), numbers, strings, booleans, undef, vectors, ranges
//    (`[a:b]`, `[a:s:b]`, OpenSCAD's count rule; `[a:b]` with a > b runs from b
//    to a, OpenSCAD's deprecated behaviour), list comprehensions (`for`,
//    `if`/`else`, `let`, `each`), `?:`, `let`, indexing and `.x/.y/.z`, the
//    arithmetic of numbers, vectors and matrices, comparisons and logic;
//  - `module` and `function` definitions with parameters and defaults,
//    `children()`, `children(i)`, `$children`; `$`-variables scoped
//    dynamically, the others lexically; `for`, `if`/`else`, `let` statements,
//    `intersection_for` when each iteration makes one node;
//    `*` (disabled) statements, `%` and `#` modifiers; `echo` and `assert`
//    as statements and in expressions; names starting with digits; a
//    variable assigned again in one scope (the last value at the first
//    place), a module body reassigning a parameter, `assign()`;
//  - `include <file>` and `use <file>` as OpenSCAD reads them
//    (evaluate_model/source_files.h: found beside the naming file, then in
//    OPENSCADPATH and OpenSCAD's library directories; a used file's modules
//    and functions see its own top-level assignments; -D values reach used
//    files too; each library file parsed once per process);
//  - built-in functions: trigonometry in degrees (exact at multiples of 30
//    and 45 as OpenSCAD's), abs, sign, sqrt, pow, exp, ln, log, floor, ceil,
//    round, min, max, norm, cross (2D and 3D), len, concat, str, chr, ord,
//    lookup, is_undef/is_num/is_bool/is_string/is_list;
//  - built-in modules: cube, sphere, cylinder, polyhedron, square, circle,
//    polygon, text (ASCII), translate, rotate, scale, mirror, multmatrix,
//    color (a vector, an SVG colour name or #hex), union, difference,
//    intersection, hull, group, render, offset, projection, linear_extrude,
//    rotate_extrude.
// Declined (the caller falls back to OpenSCAD's own export): a file included
// or used that fabatlas cannot parse (naming that file's line), import,
// surface, minkowski, resize, the `!` modifier,
// function literals, rands/search/version and other built-ins not above,
// `\x`/`\u` escapes and non-ASCII text, any operation on undef or of
// mismatched types (OpenSCAD warns and goes on with undef), recursion deeper
// than 10,000 calls or than
// 1 MiB of stack (about 250 levels of a recursive function and as many of a
// module), loops of more than 1,000,000 iterations, more than 20 million
// evaluation steps, vectors of more than a million values, more than two
// million vector values built in all (about 200 MB), strings of more than
// ten million characters, a failed assert. A color() with a name that is
// no colour is bad input (ModelEvaluation::bad_input), not declined.
//
// Numbers are written as OpenSCAD writes them (node fields as C's %g; vectors
// and matrices with 6 significant digits, exact ties away from zero, `1e+6`,
// `2.5e-7`), so an equal tree gives equal text and equal subtree keys.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace fabatlas::scad {

struct ModelEvaluation {
  bool evaluated = false;  // false: the evaluator declined; ask OpenSCAD
  std::string csg;         // the .csg text (when evaluated)
  std::string declined;    // why not, "MODEL.scad:LINE: what" (when declined)
  // The model is wrong whatever evaluates it, "MODEL.scad:LINE: what" (a
  // color() with an unknown name); also in `declined`. Report it, exit 2.
  std::string bad_input;
  // "FILE:LINE: include <x>: not found ...; skipped, as OpenSCAD does": each
  // included or used file OpenSCAD too would skip with a warning.
  std::vector<std::string> warnings;
  double seconds = 0;  // wall time of reading, parsing and evaluating
};

// Evaluates `model` with the top-level assignments of `overrides` (name,
// OpenSCAD literal, as `-D name=literal` passes them) replaced or added.
// Never throws for any model text; thread-safe (the only shared state is the
// per-process cache of parsed library files, under a lock).
ModelEvaluation EvaluateModel(const std::filesystem::path& model,
                              const std::vector<std::pair<std::string, std::string>>& overrides);

// The same for model text in memory (`file` names it in `declined`).
ModelEvaluation EvaluateModelText(const std::string& text, const std::string& file,
                                  const std::vector<std::pair<std::string, std::string>>& overrides);

// The first color() call in `text` whose literal name (`color("x")`,
// `color(c = "x")`) is no colour OpenSCAD 2021.01 knows, as
// "FILE:LINE: color(\"x\"): unknown colour name (...)", the line
// ModelEvaluation::bad_input gives; empty when there is none. Reads the text
// alone (not what it includes); a name computed at run time is the
// evaluator's to find. For models OpenSCAD evaluates (its --quiet export
// hides its own warning).
std::string UnknownColourName(const std::string& text, const std::string& file);

}  // namespace fabatlas::scad
