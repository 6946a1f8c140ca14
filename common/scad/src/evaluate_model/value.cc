// Values of evaluate_model.h's evaluator and their arithmetic
// (value.h).
#include "value.h"

#include <cmath>
#include <limits>
#include <numbers>

namespace fabatlas::scad::internal {

thread_local std::size_t Value::values_built = 0;

Value Value::Vector(std::vector<Value> v) {
  if (v.size() > 1'000'000) throw NotNative{0, "a vector of more than 1,000,000 values"};
  if ((values_built += v.size()) > 2'000'000) throw NotNative{0, "more than 2 million vector values built"};
  Value x;
  x.kind = Kind::kVector;
  x.items = std::make_shared<const std::vector<Value>>(std::move(v));
  return x;
}

bool Value::Truthy() const {
  switch (kind) {
    case Kind::kUndef:
      return false;
    case Kind::kBool:
      return boolean;
    case Kind::kNumber:
      return number != 0;
    case Kind::kString:
      return !text.empty();
    case Kind::kVector:
      return !items->empty();
    case Kind::kRange:
      return true;
  }
  return false;
}

bool Equal(const Value& a, const Value& b) {
  if (a.kind != b.kind) return false;
  switch (a.kind) {
    case Value::Kind::kUndef:
      return true;
    case Value::Kind::kBool:
      return a.boolean == b.boolean;
    case Value::Kind::kNumber:
      return a.number == b.number;
    case Value::Kind::kString:
      return a.text == b.text;
    case Value::Kind::kRange:
      return a.range[0] == b.range[0] && a.range[1] == b.range[1] && a.range[2] == b.range[2];
    case Value::Kind::kVector:
      if (a.items->size() != b.items->size()) return false;
      for (std::size_t k = 0; k < a.items->size(); ++k)
        if (!Equal((*a.items)[k], (*b.items)[k])) return false;
      return true;
  }
  return false;
}

bool AllNumbers(const Value& v) {
  if (!v.IsVector()) return false;
  for (const Value& x : v.Items())
    if (!x.IsNumber()) return false;
  return true;
}

const Value& Numbers(const Value& v, int line, const char* what) {
  if (!AllNumbers(v)) throw NotNative{line, std::string(what) + " of a non-numeric vector"};
  return v;
}

Value Negate(const Value& a, int line) {
  if (a.IsNumber()) return Value::Number(-a.number);
  if (a.IsVector()) {
    std::vector<Value> out;
    for (const Value& x : a.Items()) out.push_back(Negate(x, line));
    return Value::Vector(std::move(out));
  }
  throw NotNative{line, "negation of a non-number"};
}

Value Arithmetic(const std::string& op, const Value& a, const Value& b, int line) {
  if (a.IsNumber() && b.IsNumber()) {
    const double x = a.number, y = b.number;
    if (op == "+") return Value::Number(x + y);
    if (op == "-") return Value::Number(x - y);
    if (op == "*") return Value::Number(x * y);
    if (op == "/") return Value::Number(x / y);
    if (op == "%") return Value::Number(std::fmod(x, y));
    if (op == "^") return Value::Number(std::pow(x, y));
  }
  if ((op == "+" || op == "-") && a.IsVector() && b.IsVector()) {
    if (a.Items().size() != b.Items().size()) throw NotNative{line, "vectors of different lengths added"};
    std::vector<Value> out;
    for (std::size_t k = 0; k < a.Items().size(); ++k) out.push_back(Arithmetic(op, a.Items()[k], b.Items()[k], line));
    return Value::Vector(std::move(out));
  }
  if ((op == "*" || op == "/") && a.IsVector() && b.IsNumber()) {
    std::vector<Value> out;
    for (const Value& x : a.Items()) out.push_back(Arithmetic(op, x, b, line));
    return Value::Vector(std::move(out));
  }
  if (op == "*" && a.IsNumber() && b.IsVector()) {
    std::vector<Value> out;
    for (const Value& x : b.Items()) out.push_back(Arithmetic(op, a, x, line));
    return Value::Vector(std::move(out));
  }
  if (op == "*" && a.IsVector() && b.IsVector()) return Product(a, b, line);
  throw NotNative{line, "operator " + op + " on these operands"};
}

namespace {

// Row vector `a` times the columns of matrix `b`.
Value VectorTimesMatrix(const Value& a, const Value& b, int line) {
  if (a.Items().size() != b.Items().size()) throw NotNative{line, "vector x matrix of different sizes"};
  const std::size_t cols = b.Items()[0].IsVector() ? b.Items()[0].Items().size() : 0;
  std::vector<Value> out;
  for (std::size_t c = 0; c < cols; ++c) {
    double s = 0;
    for (std::size_t r = 0; r < b.Items().size(); ++r) {
      const Value& row = b.Items()[r];
      if (!AllNumbers(row) || row.Items().size() != cols) throw NotNative{line, "ragged matrix"};
      s += a.Items()[r].number * row.Items()[c].number;
    }
    out.push_back(Value::Number(s));
  }
  return Value::Vector(std::move(out));
}

}  // namespace

Value Product(const Value& a, const Value& b, int line) {
  if (AllNumbers(a) && AllNumbers(b)) {
    if (a.Items().size() != b.Items().size()) throw NotNative{line, "dot product of different lengths"};
    double s = 0;
    for (std::size_t k = 0; k < a.Items().size(); ++k) s += a.Items()[k].number * b.Items()[k].number;
    return Value::Number(s);
  }
  if (!a.Items().empty() && AllNumbers(b)) {  // matrix x vector: rows dotted with b
    std::vector<Value> out;
    for (const Value& row : a.Items()) {
      if (!AllNumbers(row)) throw NotNative{line, "matrix product of a ragged matrix"};
      out.push_back(Product(row, b, line));
    }
    return Value::Vector(std::move(out));
  }
  if (AllNumbers(a) && !b.Items().empty()) return VectorTimesMatrix(a, b, line);
  // matrix x matrix: each row of a times b
  std::vector<Value> out;
  for (const Value& row : a.Items()) {
    if (!AllNumbers(row)) throw NotNative{line, "matrix product of these operands"};
    out.push_back(Product(row, b, line));
  }
  return Value::Vector(std::move(out));
}

std::vector<double> RangeValues(const Value& r, int line) {
  double begin = r.range[0], step = r.range[1], end = r.range[2];
  if (!std::isfinite(begin) || !std::isfinite(step) || !std::isfinite(end) || step == 0)
    throw NotNative{line, "a range with an infinite, undefined or zero part"};
  std::vector<double> out;
  if (step < 0 ? begin < end : begin > end) return out;
  const double steps = std::nextafter((end - begin) / step, std::numeric_limits<double>::max());
  if (steps >= 1e6) throw NotNative{line, "a range of more than 1,000,000 values"};
  const auto n = static_cast<std::size_t>(steps) + 1;
  for (std::size_t i = 0; i < n; ++i) out.push_back(begin + static_cast<double>(i) * step);
  return out;
}

double SinDegrees(double x) {
  if (!std::isfinite(x)) return std::nan("");
  x = std::fmod(x, 360.0);
  if (x < 0) x += 360.0;
  bool negate = false;
  if (x >= 180.0) {
    x -= 180.0;
    negate = true;
  }
  if (x > 90.0) x = 180.0 - x;
  double s;
  if (x == 0)
    s = 0;
  else if (x == 30.0)
    s = 0.5;
  else if (x == 45.0)
    s = std::sqrt(0.5);
  else if (x == 60.0)
    s = std::sqrt(3.0) / 2;
  else if (x == 90.0)
    s = 1;
  else
    s = std::sin(x * std::numbers::pi / 180.0);
  return negate ? -s : s;
}

double CosDegrees(double x) { return SinDegrees(x + 90.0); }

}  // namespace fabatlas::scad::internal
