// fabatlas/scad/customizer.h — the parameters of an OpenSCAD model as
// OpenSCAD's Customizer reads them (OpenSCAD User Manual, "Customizer",
// for OpenSCAD 2019.05 and later).
//
// The rules followed:
//  - a parameter is a top-level assignment `name = literal;` of the main file
//    that appears before the first `{` of the file (outside comments and
//    strings); the literal is a number, a string, true/false or a vector;
//    assignments of expressions are not parameters;
//  - its widget is the trailing `// [...]` comment on the line of its `;`:
//      [max]                slider from 0
//      [min:max]            slider
//      [min:step:max]       slider with a step
//      [a, b, c]            dropdown of numbers or strings (words may be bare)
//      [a:Label, b:Label]   dropdown of labelled values
//    no annotation: a spin box / text box / check box (not a range);
//  - its description is a `//` comment starting in column 1 on the line just
//    above the assignment;
//  - `/* [Name] */` starts group Name for the assignments below it;
//    `/* [Hidden] */` hides them.
// An annotation that does not follow these rules (unterminated, a slider with
// min > max or step <= 0, a slider on a string, a default that is not one of
// the dropdown's values) leaves the parameter without a widget and adds a
// warning "FILE:LINE: ..." naming the line.
#pragma once

#include <string>
#include <vector>

namespace fabatlas::scad {

// A value as OpenSCAD writes it.
struct ScadValue {
  enum class Type { kNumber, kString, kBoolean, kVector } type = Type::kNumber;
  double number = 0;  // kNumber
  std::string text;   // kString (unescaped), kBoolean ("true"/"false"), kVector (source text)
  // The value as an OpenSCAD literal (strings quoted and escaped).
  std::string Literal() const;
};

struct DropdownOption {
  ScadValue value;
  std::string label;  // the label written after ':', else the value as text
};

struct CustomizerParameter {
  enum class Widget { kNone, kSlider, kDropdown } widget = Widget::kNone;
  std::string name;
  ScadValue value;          // the model's value
  int line = 0;             // 1-based line of the assignment
  std::string group;        // "" before the first group comment
  bool hidden = false;      // in the [Hidden] group
  std::string description;  // the comment line above, without "//"
  // Slider: min, max and step (step 0 when the annotation gave none).
  double min = 0, max = 0, step = 0;
  // Dropdown options, in order.
  std::vector<DropdownOption> options;
};

struct CustomizerModel {
  std::vector<CustomizerParameter> parameters;  // in file order
  std::vector<std::string> warnings;            // "FILE:LINE: ..." one per malformed annotation
};

// Reads the Customizer parameters from a model's text; `file` names it in
// warnings. Never throws for malformed annotations (see above).
CustomizerModel ReadCustomizer(const std::string& text, const std::string& file);

// OpenSCAD's parameter-set file (`MODEL.json` beside `MODEL.scad`):
// {"parameterSets": {"set name": {"param": "value text", ...}}, ...}.
struct ParameterSet {
  std::string name;
  std::vector<std::pair<std::string, std::string>> values;  // as written, in file order
};
// Throws fabatlas::InputError naming the file for malformed JSON.
std::vector<ParameterSet> ReadParameterSets(const std::string& json_text, const std::string& file);

// A string as an OpenSCAD string literal: "..." with \ and " escaped and
// control characters as \n, \t, \r (so `-D name=<literal>` passes it intact).
std::string QuoteScadString(const std::string& s);

// A number as OpenSCAD reads it back exactly (shortest round-trip form).
std::string FormatScadNumber(double v);

}  // namespace fabatlas::scad
