// OpenSCAD's built-in functions as evaluate_model.h implements them
// (builtin_functions.h): trigonometry in degrees, numbers, vectors,
// strings, lookup and type tests.
#include "builtin_functions.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <string_view>
#include <utility>

namespace fabatlas::scad::internal {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

// One call of a built-in function: its name, positional arguments and line.
struct FunctionCall {
  const std::string& name;
  const std::vector<Value>& a;
  int line;

  // Argument k as a number; declines "NAME() of a non-number" otherwise.
  double Number(std::size_t k) const {
    if (k >= a.size() || !a[k].IsNumber()) throw NotNative{line, name + "() of a non-number"};
    return a[k].number;
  }
  // f of the only argument, a number; declines other argument counts.
  Value One(double (*f)(double)) const {
    if (a.size() != 1) throw NotNative{line, name + "() with " + std::to_string(a.size()) + " arguments"};
    return Value::Number(f(Number(0)));
  }
  // Declines arguments the function does not take.
  [[noreturn]] void Decline() const { throw NotNative{line, "function " + name + "() with these arguments"}; }
};

using BuiltinFunction = Value (*)(const FunctionCall&);

// ---------------------------------------------------------------- numbers

Value Sin(const FunctionCall& c) {
  return c.One([](double x) { return SinDegrees(x); });
}
Value Cos(const FunctionCall& c) {
  return c.One([](double x) { return CosDegrees(x); });
}
Value Tan(const FunctionCall& c) {
  return c.One([](double x) { return SinDegrees(x) / CosDegrees(x); });
}
Value Asin(const FunctionCall& c) {
  return c.One([](double x) { return std::asin(x) * kDeg; });
}
Value Acos(const FunctionCall& c) {
  return c.One([](double x) { return std::acos(x) * kDeg; });
}
Value Atan(const FunctionCall& c) {
  return c.One([](double x) { return std::atan(x) * kDeg; });
}
Value Atan2(const FunctionCall& c) {
  if (c.a.size() != 2) c.Decline();
  return Value::Number(std::atan2(c.Number(0), c.Number(1)) * kDeg);
}
Value Abs(const FunctionCall& c) {
  return c.One([](double x) { return std::abs(x); });
}
Value Sign(const FunctionCall& c) {
  return c.One([](double x) { return x > 0 ? 1.0 : x < 0 ? -1.0 : 0.0; });
}
Value Sqrt(const FunctionCall& c) {
  return c.One([](double x) { return std::sqrt(x); });
}
Value Exp(const FunctionCall& c) {
  return c.One([](double x) { return std::exp(x); });
}
Value Ln(const FunctionCall& c) {
  return c.One([](double x) { return std::log(x); });
}
// log(x): base 10; log(b, x): base b.
Value Log(const FunctionCall& c) {
  if (c.a.size() == 1) return Value::Number(std::log10(c.Number(0)));
  if (c.a.size() == 2) return Value::Number(std::log(c.Number(1)) / std::log(c.Number(0)));
  c.Decline();
}
Value Floor(const FunctionCall& c) {
  return c.One([](double x) { return std::floor(x); });
}
Value Ceil(const FunctionCall& c) {
  return c.One([](double x) { return std::ceil(x); });
}
Value Round(const FunctionCall& c) {
  return c.One([](double x) { return std::round(x); });
}
Value Pow(const FunctionCall& c) {
  if (c.a.size() != 2) c.Decline();
  return Value::Number(std::pow(c.Number(0), c.Number(1)));
}

// min or max of the numbers given, or of the one vector given.
Value Extreme(const FunctionCall& c, bool smallest) {
  const std::vector<Value>& xs = c.a.size() == 1 && c.a[0].IsVector() ? c.a[0].Items() : c.a;
  if (xs.empty()) throw NotNative{c.line, c.name + "() of nothing"};
  double m = 0;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    if (!xs[k].IsNumber()) throw NotNative{c.line, c.name + "() of a non-number"};
    m = k == 0 ? xs[k].number : smallest ? std::min(m, xs[k].number) : std::max(m, xs[k].number);
  }
  return Value::Number(m);
}
Value Min(const FunctionCall& c) { return Extreme(c, true); }
Value Max(const FunctionCall& c) { return Extreme(c, false); }

// ---------------------------------------------------------------- vectors

Value Norm(const FunctionCall& c) {
  if (c.a.size() != 1) c.Decline();
  double s = 0;
  for (const Value& x : Numbers(c.a[0], c.line, "norm").Items()) s += x.number * x.number;
  return Value::Number(std::sqrt(s));
}

// The 3-D cross product, or the 2-D one (a number).
Value Cross(const FunctionCall& c) {
  if (c.a.size() != 2) c.Decline();
  const auto& u = Numbers(c.a[0], c.line, "cross").Items();
  const auto& v = Numbers(c.a[1], c.line, "cross").Items();
  if (u.size() == 2 && v.size() == 2) return Value::Number(u[0].number * v[1].number - u[1].number * v[0].number);
  if (u.size() != 3 || v.size() != 3) throw NotNative{c.line, "cross() of vectors not of 2 or 3 numbers"};
  return Value::Vector({Value::Number(u[1].number * v[2].number - u[2].number * v[1].number),
                        Value::Number(u[2].number * v[0].number - u[0].number * v[2].number),
                        Value::Number(u[0].number * v[1].number - u[1].number * v[0].number)});
}

Value Len(const FunctionCall& c) {
  if (c.a.size() != 1) c.Decline();
  if (c.a[0].IsVector()) return Value::Number(static_cast<double>(c.a[0].Items().size()));
  if (c.a[0].kind == Value::Kind::kString) return Value::Number(static_cast<double>(c.a[0].text.size()));
  throw NotNative{c.line, "len() of a non-vector"};
}

Value Concat(const FunctionCall& c) {
  std::vector<Value> out;
  for (const Value& x : c.a) {
    if (x.IsVector())
      out.insert(out.end(), x.Items().begin(), x.Items().end());
    else
      out.push_back(x);
    if (out.size() > 1'000'000) throw NotNative{c.line, "a vector of more than 1,000,000 values"};
  }
  return Value::Vector(std::move(out));
}

// OpenSCAD: below the first key the first value, above the last the last,
// else linear between the neighbouring keys (table in order).
Value Lookup(const FunctionCall& c) {
  if (c.a.size() != 2) c.Decline();
  const double key = c.Number(0);
  if (!c.a[1].IsVector() || c.a[1].Items().empty()) throw NotNative{c.line, "lookup() in a non-table"};
  std::vector<std::pair<double, double>> table;
  for (const Value& row : c.a[1].Items()) {
    if (!AllNumbers(row) || row.Items().size() < 2) throw NotNative{c.line, "lookup() in a malformed table"};
    table.push_back({row.Items()[0].number, row.Items()[1].number});
  }
  double low_key = table[0].first, low = table[0].second, high_key = low_key, high = low;
  bool have_low = false, have_high = false;
  for (const auto& [k, v] : table) {
    if (k <= key && (!have_low || k > low_key)) low_key = k, low = v, have_low = true;
    if (k >= key && (!have_high || k < high_key)) high_key = k, high = v, have_high = true;
  }
  if (!have_low) return Value::Number(high);
  if (!have_high) return Value::Number(low);
  if (high_key == low_key) return Value::Number(low);
  return Value::Number(low + (key - low_key) / (high_key - low_key) * (high - low));
}

// ---------------------------------------------------------------- strings

Value Str(const FunctionCall& c) {
  std::string out;
  for (const Value& x : c.a) {
    if (x.kind == Value::Kind::kString)
      out += x.text;
    else if (x.IsNumber() && std::isfinite(x.number))
      out += ValueNum(x.number);
    else if (x.kind == Value::Kind::kBool)
      out += x.boolean ? "true" : "false";
    else
      throw NotNative{c.line, "str() of a vector, infinity or undef"};
    if (out.size() > 10'000'000) throw NotNative{c.line, "a string of more than 10,000,000 characters"};
  }
  return Value::String(out);
}

Value Chr(const FunctionCall& c) {
  std::string out;
  for (const Value& x : c.a) {
    if (!x.IsNumber() || x.number < 1 || x.number > 127) throw NotNative{c.line, "chr() outside ASCII"};
    out += static_cast<char>(x.number);
  }
  return Value::String(out);
}

// The code of a one-character ASCII string.
Value Ord(const FunctionCall& c) {
  if (c.a.size() != 1 || c.a[0].kind != Value::Kind::kString || c.a[0].text.size() != 1 ||
      static_cast<unsigned char>(c.a[0].text[0]) >= 0x80)
    c.Decline();
  return Value::Number(static_cast<unsigned char>(c.a[0].text[0]));
}

// ---------------------------------------------------------------- type tests

// is_undef, is_num (NaN is not), is_bool, is_string, is_list of one value.
template <bool (*kTest)(const Value&)>
Value IsA(const FunctionCall& c) {
  if (c.a.size() != 1) c.Decline();
  return Value::Bool(kTest(c.a[0]));
}
bool Undefined(const Value& v) { return v.kind == Value::Kind::kUndef; }
bool ANumber(const Value& v) { return v.IsNumber() && !std::isnan(v.number); }
bool ABool(const Value& v) { return v.kind == Value::Kind::kBool; }
bool AString(const Value& v) { return v.kind == Value::Kind::kString; }
bool AList(const Value& v) { return v.IsVector(); }

const std::map<std::string_view, BuiltinFunction> kFunctions = {
    {"sin", Sin},
    {"cos", Cos},
    {"tan", Tan},
    {"asin", Asin},
    {"acos", Acos},
    {"atan", Atan},
    {"atan2", Atan2},
    {"abs", Abs},
    {"sign", Sign},
    {"sqrt", Sqrt},
    {"exp", Exp},
    {"ln", Ln},
    {"log", Log},
    {"floor", Floor},
    {"ceil", Ceil},
    {"round", Round},
    {"pow", Pow},
    {"min", Min},
    {"max", Max},
    {"norm", Norm},
    {"cross", Cross},
    {"len", Len},
    {"concat", Concat},
    {"str", Str},
    {"chr", Chr},
    {"ord", Ord},
    {"lookup", Lookup},
    {"is_undef", IsA<Undefined>},
    {"is_num", IsA<ANumber>},
    {"is_bool", IsA<ABool>},
    {"is_string", IsA<AString>},
    {"is_list", IsA<AList>},
};

}  // namespace

Value CallBuiltinFunction(const std::string& name, const std::vector<Value>& args, int line) {
  const FunctionCall call{name, args, line};
  auto it = kFunctions.find(name);
  if (it == kFunctions.end()) call.Decline();
  return it->second(call);
}

}  // namespace fabatlas::scad::internal
