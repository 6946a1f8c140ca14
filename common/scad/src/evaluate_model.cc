// A Customizer model's CSG tree evaluated natively (fabatlas/scad/evaluate_model.h):
// the model parsed (evaluate_model/parser.h), its -D overrides applied, evaluated
// (evaluate_model/evaluator.h) and written as OpenSCAD's .csg export
// (evaluate_model/csg_node.h); any NotNative on the way declines, naming the line.
#include "fabatlas/scad/evaluate_model.h"

#include <fstream>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "fabatlas/scad/lex_source.h"
#include "fabatlas/stopwatch.h"
#include "evaluate_model/colours.h"
#include "evaluate_model/csg_node.h"
#include "evaluate_model/evaluator.h"
#include "evaluate_model/parser.h"
#include "evaluate_model/scope.h"
#include "evaluate_model/source_files.h"
#include "evaluate_model/syntax.h"
#include "evaluate_model/value.h"

namespace fabatlas::scad {
namespace {

using internal::BadModel;
using internal::CsgOut;
using internal::ExprPtr;
using internal::NotNative;
using internal::Parser;
using internal::Scope;
using internal::Stmt;
using internal::StmtPtr;
using internal::Value;

// The value of -D name=literal.
ExprPtr OverrideValue(const std::string& name, const std::string& literal) {
  try {
    return Parser(internal::Lex(literal)).OneExpression();
  } catch (NotNative& e) {
    e.line = 0;
    e.what = "the value of -D " + name + "=" + literal + ": " + e.what;
    throw;
  }
}

// The scope above the model's: the special variables' defaults and PI.
Scope BuiltinScope() {
  Scope builtins;
  builtins.vars["$fn"] = Value::Number(0);
  builtins.vars["$fa"] = Value::Number(12);
  builtins.vars["$fs"] = Value::Number(2);
  builtins.vars["$t"] = Value::Number(0);
  builtins.vars["$preview"] = Value::Bool(false);
  builtins.vars["$children"] = Value::Number(0);
  builtins.vars["PI"] = Value::Number(std::numbers::pi);
  return builtins;
}

}  // namespace

ModelEvaluation EvaluateModelText(const std::string& text, const std::string& file,
                                  const std::vector<std::pair<std::string, std::string>>& overrides) {
  const Stopwatch watch;
  ModelEvaluation result;
  Value::values_built = 0;
  try {
    const std::shared_ptr<const internal::SourceFile> model = internal::ParseModel(text, file);
    result.warnings = model->warnings;
    std::vector<StmtPtr> program = model->statements;
    std::vector<std::pair<std::string, ExprPtr>> values;
    for (const auto& [name, literal] : overrides) {
      values.emplace_back(name, OverrideValue(name, literal));
      internal::Override(program, name, values.back().second);
    }
    const Scope builtins = BuiltinScope();
    Scope top;
    top.lexical = top.dynamic = &builtins;
    top.uses = &model->uses;
    std::vector<CsgOut> roots;
    internal::Evaluator(&builtins, std::move(values)).Run(program, top, roots);
    for (const CsgOut& r : roots) internal::Print(r, 0, result.csg);
    result.csg += "\n";  // OpenSCAD ends its export with an empty line
    result.evaluated = true;
  } catch (const BadModel& e) {
    result.csg.clear();
    result.bad_input = (e.file.empty() ? file : e.file) + ":" + std::to_string(e.line) + ": " + e.what;
    result.declined = result.bad_input;
  } catch (const NotNative& e) {
    result.csg.clear();
    result.declined =
        (e.file.empty() ? file : e.file) + (e.line > 0 ? ":" + std::to_string(e.line) : std::string()) + ": " + e.what;
  }
  result.seconds = watch.Seconds();
  return result;
}

ModelEvaluation EvaluateModel(const std::filesystem::path& model,
                              const std::vector<std::pair<std::string, std::string>>& overrides) {
  const Stopwatch watch;
  std::ifstream in(model, std::ios::binary);
  if (!in) {
    ModelEvaluation result;
    result.declined = model.string() + ": cannot be read";
    return result;
  }
  std::stringstream text;
  text << in.rdbuf();
  ModelEvaluation result = EvaluateModelText(text.str(), model.string(), overrides);
  result.seconds = watch.Seconds();
  return result;
}

std::string UnknownColourName(const std::string& text, const std::string& file) {
  const std::vector<SourceToken> t = LexSource(text).tokens;
  auto symbol = [&](std::size_t i, const char* s) {
    return i < t.size() && t[i].kind == SourceToken::Kind::kSymbol && t[i].text == s;
  };
  for (std::size_t i = 0; i + 2 < t.size(); ++i) {
    if (t[i].kind != SourceToken::Kind::kIdent || t[i].text != "color" || !symbol(i + 1, "(")) continue;
    std::size_t at = i + 2;
    if (t[at].kind == SourceToken::Kind::kIdent && t[at].text == "c" && symbol(at + 1, "=")) at += 2;
    if (at + 1 >= t.size() || t[at].kind != SourceToken::Kind::kString || !(symbol(at + 1, ")") || symbol(at + 1, ",")))
      continue;
    double rgba[4];
    if (!internal::ColourByName(t[at].text, rgba))
      return file + ":" + std::to_string(t[at].line) + ": " + internal::UnknownColourText(t[at].text);
  }
  return {};
}

}  // namespace fabatlas::scad
