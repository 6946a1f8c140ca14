// Values as OpenSCAD 2021.01 writes them in a .csg export (value.h).
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "value.h"

namespace fabatlas::scad::internal {

std::string Num(double v) {
  if (v == 0) v = 0;  // -0 is written 0
  char buf[40];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::string ValueNum(double v) {
  if (v == 0) return "0";
  if (!std::isfinite(v)) return std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf";
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.80e", std::abs(v));  // exact decimal digits of the double
  const std::string text = buf;
  const std::size_t e_at = text.find('e');
  std::string digits = text.substr(0, 1) + text.substr(2, e_at - 2);
  int exponent = std::stoi(text.substr(e_at + 1));
  std::string six = digits.substr(0, 6);
  if (digits[6] >= '5') {
    int k = 5;
    while (k >= 0 && six[k] == '9') six[k--] = '0';
    if (k < 0) {
      six = "100000";
      ++exponent;
    } else {
      ++six[k];
    }
  }
  while (six.size() > 1 && six.back() == '0') six.pop_back();
  std::string out = v < 0 ? "-" : "";
  if (exponent < -6 || exponent >= 6) {
    out += six.substr(0, 1);
    if (six.size() > 1) out += "." + six.substr(1);
    out += (exponent < 0 ? "e-" : "e+") + std::to_string(std::abs(exponent));
  } else if (exponent < 0) {
    out += "0." + std::string(-exponent - 1, '0') + six;
  } else {
    const std::size_t whole = static_cast<std::size_t>(exponent) + 1;
    if (six.size() <= whole) {
      out += six + std::string(whole - six.size(), '0');
    } else {
      out += six.substr(0, whole) + "." + six.substr(whole);
    }
  }
  return out;
}

std::string Quote(const std::string& s, int line) {
  for (char c : s)
    if (c == '"' || c == '\\' || static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x80)
      throw NotNative{line, "a string with quotes, backslashes, control or non-ASCII characters"};
  return "\"" + s + "\"";
}

std::string Write(const Value& v, int line) {
  switch (v.kind) {
    case Value::Kind::kUndef:
      return "undef";
    case Value::Kind::kBool:
      return v.boolean ? "true" : "false";
    case Value::Kind::kNumber:
      return ValueNum(v.number);
    case Value::Kind::kString:
      return Quote(v.text, line);
    case Value::Kind::kRange:
      throw NotNative{line, "a range as an argument"};
    case Value::Kind::kVector: {
      std::string out = "[";
      for (std::size_t k = 0; k < v.items->size(); ++k) out += (k ? ", " : "") + Write((*v.items)[k], line);
      return out + "]";
    }
  }
  return "undef";
}

}  // namespace fabatlas::scad::internal
