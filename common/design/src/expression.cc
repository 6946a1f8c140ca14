#include "expression.h"

#include <muParser.h>

#include <cmath>

#include "fabatlas/error.h"

namespace fabatlas::design {

Scope::Scope(const std::vector<std::string>& names) : names_(names), values_(names.size(), 0.0) {
  for (std::size_t i = 0; i < names.size(); ++i) index_[names[i]] = i;
}

double* Scope::Slot(const std::string& name) {
  auto it = index_.find(name);
  return it == index_.end() ? nullptr : &values_[it->second];
}

void Scope::Set(const std::string& name, double value) {
  double* slot = Slot(name);
  if (slot) *slot = value;
}

double Scope::Get(const std::string& name) const {
  auto it = index_.find(name);
  return it == index_.end() ? std::nan("") : values_[it->second];
}

namespace {

// muparser reports unknown names as "Unexpected token" with the token; make
// the message say what a designer needs to hear.
std::string Describe(const mu::Parser::exception_type& e) {
  switch (e.GetCode()) {
    case mu::ecUNASSIGNABLE_TOKEN:
      return "unknown name '" + e.GetToken() + "' in expression";
    default:
      return e.GetMsg();
  }
}

}  // namespace

Expression::Expression(const std::string& text, Scope& scope, const SourcePlace& place)
    : text_(text), place_(place), parser_(std::make_unique<mu::Parser>()) {
  try {
    for (const std::string& name : scope.names()) parser_->DefineVar(name, scope.Slot(name));
    parser_->DefineConst("pi", M_PI);
    parser_->SetExpr(text);
    parser_->Eval();  // compiles and checks every name now, not at first use
  } catch (const mu::Parser::exception_type& e) {
    throw InputError(place.str() + ": " + Describe(e) + " in '" + text + "'");
  }
}

Expression::~Expression() = default;
Expression::Expression(Expression&&) noexcept = default;
Expression& Expression::operator=(Expression&&) noexcept = default;

double Expression::Evaluate() const {
  try {
    return parser_->Eval();
  } catch (const mu::Parser::exception_type& e) {
    throw InputError(place_.str() + ": " + Describe(e) + " in '" + text_ + "'");
  }
}

std::vector<std::string> Expression::Names() const {
  std::vector<std::string> names;
  for (const auto& [name, _] : parser_->GetUsedVar()) names.push_back(name);
  return names;
}

std::vector<std::string> ParameterNames(const Design& design) {
  std::vector<std::string> names;
  for (const auto& p : design.exposed) names.push_back(p.name);
  for (const auto& p : design.mutables) names.push_back(p.name);
  return names;
}

}  // namespace fabatlas::design
