// Internal: expressions over design parameters, compiled with muparser.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "fabatlas/design/design.h"

namespace mu {
class Parser;
}

namespace fabatlas::design {

// Named parameter values that expressions read. Addresses are stable: the
// values live in a vector sized at construction.
class Scope {
 public:
  explicit Scope(const std::vector<std::string>& names);
  double* Slot(const std::string& name);  // nullptr if unknown
  const std::vector<std::string>& names() const { return names_; }
  void Set(const std::string& name, double value);
  double Get(const std::string& name) const;

 private:
  std::vector<std::string> names_;
  std::vector<double> values_;
  std::map<std::string, std::size_t> index_;
};

// One compiled expression bound to a Scope. Not thread-safe; cheap to build.
class Expression {
 public:
  // Throws InputError "place: message" on syntax errors and unknown names.
  Expression(const std::string& text, Scope& scope, const SourcePlace& place);
  ~Expression();
  Expression(Expression&&) noexcept;
  Expression& operator=(Expression&&) noexcept;

  // Evaluates with the scope's current values. Throws InputError on
  // evaluation errors (e.g. division by zero yields inf: reported by callers).
  double Evaluate() const;
  const std::string& text() const { return text_; }
  // The scope's names the expression reads (muparser's used variables).
  std::vector<std::string> Names() const;

 private:
  std::string text_;
  SourcePlace place_;
  std::unique_ptr<mu::Parser> parser_;
};

// Names every expression may use: exposed then mutable parameter names.
std::vector<std::string> ParameterNames(const Design& design);

}  // namespace fabatlas::design
