// evaluate_model/scope.h (internal to fabatlas_scad) — the scopes of evaluate_model.h's
// evaluator: variables, functions and modules found along the lexical
// chain, `$`-variables along the dynamic one (the caller's), as OpenSCAD
// scopes them (OpenSCAD User Manual, "Variables" and "Special variables").
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "syntax.h"
#include "value.h"

namespace fabatlas::scad::internal {

struct Scope {
  const Scope* lexical = nullptr;  // variables, functions, modules
  const Scope* dynamic = nullptr;  // $-variables
  std::map<std::string, Value> vars;
  std::map<std::string, std::shared_ptr<const ModuleDef>> modules;
  std::map<std::string, std::shared_ptr<const FunctionDef>> functions;
  // A module body's scope: the instantiation's child statements and the
  // scope they were written in.
  bool module_body = false;
  const std::vector<StmtPtr>* children = nullptr;
  const Scope* children_scope = nullptr;
  // A file's top-level scope: the files it uses (source_files.h), whose
  // top-level modules and functions it sees after its own.
  const std::vector<std::string>* uses = nullptr;

  // The variable `name` ($-variables dynamically, the others lexically), or
  // nullptr.
  const Value* Find(const std::string& name) const {
    const bool special = !name.empty() && name[0] == '$';
    for (const Scope* s = this; s; s = special ? s->dynamic : s->lexical) {
      auto it = s->vars.find(name);
      if (it != s->vars.end()) return &it->second;
    }
    return nullptr;
  }
  // The innermost module body this scope is in, or nullptr at top level.
  const Scope* Body() const {
    for (const Scope* s = this; s; s = s->lexical)
      if (s->module_body) return s;
    return nullptr;
  }
};

}  // namespace fabatlas::scad::internal
