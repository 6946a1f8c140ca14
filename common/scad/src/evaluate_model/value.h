// evaluate_model/value.h (internal to fabatlas_scad) — the values of evaluate_model.h's
// evaluator (OpenSCAD's undef, booleans, numbers, strings, vectors and
// ranges), their arithmetic, and their text as OpenSCAD 2021.01 writes it in
// a .csg export. Every operation OpenSCAD would only warn about (and go on
// with undef) declines with NotNative.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "syntax.h"

namespace fabatlas::scad::internal {

struct Value {
  // Vector values built by this thread's evaluation (reset for each model):
  // bounds the memory a model can hold (about 100 bytes a value, at most two
  // million values), which the step count does not (one concat copies a
  // whole vector).
  static thread_local std::size_t values_built;

  enum class Kind { kUndef, kBool, kNumber, kString, kVector, kRange } kind = Kind::kUndef;
  double number = 0;  // kNumber
  bool boolean = false;
  std::string text;
  std::shared_ptr<const std::vector<Value>> items;  // kVector
  double range[3] = {0, 1, 0};                      // begin, step, end

  static Value Number(double v) {
    Value x;
    x.kind = Kind::kNumber;
    x.number = v;
    return x;
  }
  static Value Bool(bool v) {
    Value x;
    x.kind = Kind::kBool;
    x.boolean = v;
    return x;
  }
  static Value String(std::string v) {
    Value x;
    x.kind = Kind::kString;
    x.text = std::move(v);
    return x;
  }
  // Declines vectors of more than a million values and more than two
  // million values built in all.
  static Value Vector(std::vector<Value> v);
  bool IsNumber() const { return kind == Kind::kNumber; }
  bool IsVector() const { return kind == Kind::kVector; }
  const std::vector<Value>& Items() const { return *items; }
  // OpenSCAD's truth of a value (undef, false, 0, "" and [] are false).
  bool Truthy() const;
};

// OpenSCAD's == (same kind and equal contents).
bool Equal(const Value& a, const Value& b);

// Whether v is a vector of numbers only.
bool AllNumbers(const Value& v);
// v, declining "<what> of a non-numeric vector" unless AllNumbers(v).
const Value& Numbers(const Value& v, int line, const char* what);

// Unary minus of a number or (element-wise) a vector.
Value Negate(const Value& a, int line);
// Binary `op` (+ - * / % ^) of numbers, + and - of vectors of equal length,
// vector * or / number, number * vector, and the products of Product.
Value Arithmetic(const std::string& op, const Value& a, const Value& b, int line);
// Vector x vector (dot), matrix x vector, vector x matrix, matrix x matrix.
Value Product(const Value& a, const Value& b, int line);

// The values a range runs through (OpenSCAD's RangeType: count by
// nextafter((end - begin) / step) + 1; `[a:b]` with a > b swapped).
std::vector<double> RangeValues(const Value& r, int line);

// Sine and cosine of degrees, exact at multiples of 30 and 45 degrees as
// OpenSCAD's sin_degrees and cos_degrees are.
double SinDegrees(double x);
double CosDegrees(double x);

// Text (value_text.cc).

// OpenSCAD's number text in the .csg export (an ostream's default: 6
// significant digits).
std::string Num(double v);
// OpenSCAD's number text for values (vectors such as polygon points, str())
// and matrices: 6 significant digits, exact ties rounded away from zero,
// trailing zeros dropped, the exponent form (`1e+6`, `2.5e-7`) below 1e-6 and
// from 1e6.
std::string ValueNum(double v);
// A string literal as OpenSCAD writes it; declines quotes, backslashes,
// control and non-ASCII characters.
std::string Quote(const std::string& s, int line);
// A value as OpenSCAD writes an argument; declines ranges.
std::string Write(const Value& v, int line);

}  // namespace fabatlas::scad::internal
