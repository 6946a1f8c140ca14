// Reads OpenSCAD Customizer annotations (fabatlas/scad/customizer.h).
#include "fabatlas/scad/customizer.h"

#include <nlohmann/json.hpp>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/scad/lex_source.h"

namespace fabatlas::scad {
namespace {

using Token = SourceToken;

std::string Trim(const std::string& s) {
  std::size_t a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  std::size_t b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

bool ParseNumber(const std::string& s, double& out) {
  std::string t = Trim(s);
  if (t.empty()) return false;
  char* end = nullptr;
  out = std::strtod(t.c_str(), &end);
  if (end != t.c_str() + t.size() || !std::isfinite(out)) return false;
  // strtod accepts "inf", "nan", hex: OpenSCAD numbers are decimal.
  for (char c : t)
    if (!(std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E'))
      return false;
  return true;
}

// The tokens of an OpenSCAD file, comments included (lex_source.h); its
// problems are OpenSCAD's to report, so they are not looked at here.
std::vector<Token> Lex(const std::string& s) {
  LexOptions options;
  options.keep_comments = true;
  return LexSource(s, options).tokens;
}

// tokens[b, e) as a literal value, if they are one.
bool LiteralOf(const std::vector<Token>& t, std::size_t b, std::size_t e, ScadValue& v) {
  if (e - b == 1 && t[b].kind == Token::Kind::kNumber) {
    v.type = ScadValue::Type::kNumber;
    return ParseNumber(t[b].text, v.number);
  }
  if (e - b == 2 && t[b].kind == Token::Kind::kSymbol && (t[b].text == "-" || t[b].text == "+") &&
      t[b + 1].kind == Token::Kind::kNumber) {
    v.type = ScadValue::Type::kNumber;
    if (!ParseNumber(t[b + 1].text, v.number)) return false;
    if (t[b].text == "-") v.number = -v.number;
    return true;
  }
  if (e - b == 1 && t[b].kind == Token::Kind::kString) {
    v.type = ScadValue::Type::kString;
    v.text = t[b].text;
    return true;
  }
  if (e - b == 1 && t[b].kind == Token::Kind::kIdent && (t[b].text == "true" || t[b].text == "false")) {
    v.type = ScadValue::Type::kBoolean;
    v.text = t[b].text;
    return true;
  }
  if (e - b >= 2 && t[b].text == "[" && t[e - 1].text == "]") {
    // A vector of literals: numbers, strings, booleans, nested vectors.
    std::string text;
    for (std::size_t k = b; k < e; ++k) {
      const Token& x = t[k];
      if (x.kind == Token::Kind::kSymbol && std::string("[],-+").find(x.text) == std::string::npos) return false;
      if (x.kind == Token::Kind::kIdent && x.text != "true" && x.text != "false") return false;
      text += x.kind == Token::Kind::kString ? QuoteScadString(x.text) : x.text;
      if (x.text == ",") text += " ";
    }
    v.type = ScadValue::Type::kVector;
    v.text = text;
    return true;
  }
  return false;
}

// Splits at `sep` outside double quotes.
std::vector<std::string> SplitOutsideQuotes(const std::string& s, char sep) {
  std::vector<std::string> parts(1);
  bool quoted = false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    char c = s[i];
    if (c == '\\' && quoted && i + 1 < s.size()) {
      parts.back() += c;
      parts.back() += s[++i];
      continue;
    }
    if (c == '"') quoted = !quoted;
    if (c == sep && !quoted)
      parts.emplace_back();
    else
      parts.back() += c;
  }
  return parts;
}

// A dropdown value as written: "quoted string", a number, or a bare word.
ScadValue OptionValue(const std::string& written) {
  ScadValue v;
  std::string t = Trim(written);
  if (t.size() >= 2 && t.front() == '"' && t.back() == '"') {
    v.type = ScadValue::Type::kString;
    std::vector<Token> tokens = Lex(t);
    v.text = tokens.empty() ? "" : tokens[0].text;
  } else if (ParseNumber(t, v.number)) {
    v.type = ScadValue::Type::kNumber;
  } else {
    v.type = ScadValue::Type::kString;
    v.text = t;
  }
  return v;
}

std::string Display(const ScadValue& v) {
  return v.type == ScadValue::Type::kNumber ? FormatScadNumber(v.number) : v.text;
}

bool SameValue(const ScadValue& a, const ScadValue& b) {
  if (a.type != b.type) return false;
  return a.type == ScadValue::Type::kNumber ? a.number == b.number : a.text == b.text;
}

// Reads the trailing `// [...]` annotation into p. Returns "" or the reason
// the annotation is malformed.
std::string Annotate(CustomizerParameter& p, const std::string& comment) {
  std::string c = Trim(comment);
  if (c.empty() || c.front() != '[') return "";  // a plain comment, not an annotation
  std::size_t close = std::string::npos;
  bool quoted = false;
  for (std::size_t i = 1; i < c.size(); ++i) {
    if (c[i] == '\\' && quoted)
      ++i;
    else if (c[i] == '"')
      quoted = !quoted;
    else if (c[i] == ']' && !quoted) {
      close = i;
      break;
    }
  }
  if (close == std::string::npos) return "annotation '" + c + "' has no closing ']'";
  std::string inner = Trim(c.substr(1, close - 1));
  if (inner.empty()) return "annotation '[]' lists no values";
  std::vector<std::string> items = SplitOutsideQuotes(inner, ',');
  if (items.size() == 1) {
    std::vector<std::string> parts = SplitOutsideQuotes(inner, ':');
    std::vector<double> numbers;
    for (const auto& part : parts) {
      double x = 0;
      if (ParseNumber(part, x)) numbers.push_back(x);
    }
    if (numbers.size() == parts.size()) {  // a slider: [max], [min:max], [min:step:max]
      if (parts.size() > 3) return "slider '[" + inner + "]' has more than min:step:max";
      if (p.value.type != ScadValue::Type::kNumber) return "slider '[" + inner + "]' on a value that is not a number";
      p.min = parts.size() == 1 ? 0 : numbers.front();
      p.max = numbers.back();
      p.step = parts.size() == 3 ? numbers[1] : 0;
      if (p.min > p.max) return "slider '[" + inner + "]' has min > max";
      if (parts.size() == 3 && p.step <= 0) return "slider '[" + inner + "]' has a step <= 0";
      if (p.value.number < p.min || p.value.number > p.max)
        return "value " + FormatScadNumber(p.value.number) + " lies outside the slider '[" + inner + "]'";
      p.widget = CustomizerParameter::Widget::kSlider;
      return "";
    }
    if (parts.size() > 2) return "'[" + inner + "]' is neither a slider of numbers nor a value:label";
  }
  for (const auto& item : items) {
    if (Trim(item).empty()) return "dropdown '[" + inner + "]' has an empty entry";
    std::vector<std::string> parts = SplitOutsideQuotes(item, ':');
    DropdownOption o;
    o.value = OptionValue(parts[0]);
    if (parts.size() > 1) {
      std::string label = item.substr(item.find(':', parts[0].size()) + 1);
      o.label = Trim(label);
    } else {
      o.label = Display(o.value);
    }
    // A number dropdown on a string value lists strings that look like numbers.
    if (p.value.type == ScadValue::Type::kString && o.value.type == ScadValue::Type::kNumber) {
      o.value.type = ScadValue::Type::kString;
      o.value.text = Trim(parts[0]);
    }
    p.options.push_back(o);
  }
  if (p.value.type != ScadValue::Type::kNumber && p.value.type != ScadValue::Type::kString)
    return "dropdown '[" + inner + "]' on a value that is neither a number nor a string";
  bool found = false;
  for (const auto& o : p.options) {
    if (o.value.type != p.value.type)
      return "dropdown '[" + inner + "]' mixes numbers and strings with the value " + p.value.Literal();
    found = found || SameValue(o.value, p.value);
  }
  if (!found) return "value " + p.value.Literal() + " is not one of the dropdown's values '[" + inner + "]'";
  p.widget = CustomizerParameter::Widget::kDropdown;
  return "";
}

}  // namespace

std::string ScadValue::Literal() const {
  switch (type) {
    case Type::kNumber:
      return FormatScadNumber(number);
    case Type::kString:
      return QuoteScadString(text);
    case Type::kBoolean:
    case Type::kVector:
      return text;
  }
  return text;
}

std::string QuoteScadString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\r') {
      out += "\\r";
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string FormatScadNumber(double v) {
  char buf[64];
  if (v == 0) return "0";
  if (std::abs(v) >= 1e-6 && std::abs(v) < 1e15) {
    for (int decimals = 0; decimals <= 20; ++decimals) {  // plain decimals, fewest digits that read back exactly
      std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
      if (std::strtod(buf, nullptr) == v) return buf;
    }
  }
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

namespace {

bool IsComment(const Token& t) { return t.kind == Token::Kind::kLineComment || t.kind == Token::Kind::kBlockComment; }

// The tokens of an assignment's value after its '=' at `eq`, up to the ';' at
// bracket depth 0 (comments skipped); `*end` is the ';' (or t.size()),
// `*brace` whether a '{' came first (it ends the parameters).
std::vector<Token> ValueTokens(const std::vector<Token>& t, std::size_t eq, std::size_t* end, bool* brace) {
  std::vector<Token> value;
  std::size_t k = eq + 1;
  int depth = 0;
  *brace = false;
  for (; k < t.size(); ++k) {
    const Token& x = t[k];
    if (IsComment(x)) continue;
    if (x.kind == Token::Kind::kSymbol) {
      if (x.text == "{") *brace = true;
      if (x.text == "[" || x.text == "(") ++depth;
      if (x.text == "]" || x.text == ")") --depth;
      if (x.text == ";" && depth <= 0) break;
    }
    value.push_back(x);
  }
  *end = k;
  return value;
}

// The annotation: the first line comment after the ';' at `semicolon` on its
// line. A malformed one keeps the parameter fixed, with a warning.
void ReadAnnotation(const std::vector<Token>& t, std::size_t semicolon, const std::string& file, CustomizerParameter& p,
                    std::vector<std::string>& warnings) {
  const int end_line = t[semicolon].line;
  for (std::size_t m = semicolon + 1; m < t.size() && t[m].line == end_line; ++m) {
    if (t[m].kind == Token::Kind::kLineComment) {
      std::string problem = Annotate(p, t[m].text);
      if (!problem.empty()) {
        p.widget = CustomizerParameter::Widget::kNone;
        p.options.clear();
        warnings.push_back(file + ":" + std::to_string(end_line) + ": parameter '" + p.name + "': " + problem +
                           "; kept fixed at " + p.value.Literal());
      }
      return;
    }
    if (t[m].kind != Token::Kind::kBlockComment) return;
  }
}

// A later assignment of the same name replaces the earlier (OpenSCAD's rule).
void Keep(CustomizerModel& model, CustomizerParameter p) {
  for (auto& earlier : model.parameters)
    if (earlier.name == p.name) {
      earlier = p;
      return;
    }
  model.parameters.push_back(std::move(p));
}

}  // namespace

CustomizerModel ReadCustomizer(const std::string& text, const std::string& file) {
  CustomizerModel model;
  std::vector<std::string> lines;
  {
    std::istringstream in(text);
    std::string l;
    while (std::getline(in, l)) lines.push_back(l);
  }
  const std::vector<Token> t = Lex(text);
  std::string group;
  bool hidden = false;
  bool statement_start = true;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const Token& tok = t[i];
    if (tok.kind == Token::Kind::kBlockComment) {  // /* [Group] */
      std::string body = Trim(tok.text);
      if (body.size() >= 2 && body.front() == '[' && body.back() == ']') {
        group = Trim(body.substr(1, body.size() - 2));
        hidden = group == "Hidden";
      }
      continue;
    }
    if (tok.kind == Token::Kind::kLineComment) continue;
    if (tok.kind == Token::Kind::kSymbol && tok.text == "{") break;  // parameters end at the first '{'
    if (tok.kind == Token::Kind::kSymbol && tok.text == ";") {
      statement_start = true;
      continue;
    }
    bool at_start = statement_start;
    statement_start = false;
    if (!at_start || tok.kind != Token::Kind::kIdent) continue;
    if ((tok.text == "use" || tok.text == "include") && i + 1 < t.size() && t[i + 1].text == "<") {
      // `use <file>` and `include <file>` end without a ';' at their '>'.
      while (i < t.size() && !(t[i].kind == Token::Kind::kSymbol && t[i].text == ">")) ++i;
      statement_start = true;
      continue;
    }
    // name = <tokens> ; at bracket depth 0, comments skipped.
    std::size_t eq = i + 1;
    while (eq < t.size() && IsComment(t[eq])) ++eq;
    if (eq >= t.size() || t[eq].kind != Token::Kind::kSymbol || t[eq].text != "=") continue;
    std::size_t k = 0;
    bool brace = false;
    const std::vector<Token> value = ValueTokens(t, eq, &k, &brace);
    if (brace || k >= t.size()) break;  // a '{' inside the expression ends the parameters too
    i = k;                              // the ';'
    statement_start = true;
    CustomizerParameter p;
    p.name = tok.text;
    p.line = tok.line;
    p.group = group;
    p.hidden = hidden;
    if (value.empty() || !LiteralOf(value, 0, value.size(), p.value)) continue;  // an expression: not a parameter
    if (p.line >= 2 && p.line - 2 < static_cast<int>(lines.size())) {
      const std::string& above = lines[p.line - 2];
      if (above.rfind("//", 0) == 0) p.description = Trim(above.substr(2));
    }
    ReadAnnotation(t, k, file, p, model.warnings);
    Keep(model, std::move(p));
  }
  return model;
}

std::vector<ParameterSet> ReadParameterSets(const std::string& json_text, const std::string& file) {
  nlohmann::ordered_json j;
  try {
    j = nlohmann::ordered_json::parse(json_text);
  } catch (const std::exception& e) {
    throw InputError(file + ": not valid JSON: " + e.what());
  }
  std::vector<ParameterSet> sets;
  if (!j.is_object() || !j.contains("parameterSets")) return sets;
  const auto& all = j["parameterSets"];
  if (!all.is_object()) throw InputError(file + ": 'parameterSets' must be an object of named sets");
  for (auto it = all.begin(); it != all.end(); ++it) {
    if (!it.value().is_object()) throw InputError(file + ": parameter set '" + it.key() + "' must be an object");
    ParameterSet s;
    s.name = it.key();
    for (auto v = it.value().begin(); v != it.value().end(); ++v)
      s.values.emplace_back(v.key(), v.value().is_string() ? v.value().get<std::string>() : v.value().dump());
    sets.push_back(std::move(s));
  }
  return sets;
}

}  // namespace fabatlas::scad
