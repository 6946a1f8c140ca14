// The box of a model's solid from its CSG tree (fabatlas/scad/model_bounds.h).
#include "fabatlas/scad/model_bounds.h"

#include <stdlib.h>

#include <fstream>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/scad/evaluate_model.h"

namespace fabatlas::scad {
namespace {

CsgBox Unknown(const std::filesystem::path& model, const std::string& why) {
  CsgBox box;
  box.known = false;
  box.unknown = model.string() + ": " + why;
  return box;
}

// OpenSCAD's own CSG export of `model` (no mesh is built); empty on failure,
// `why` saying why.
std::string OpenScadCsg(const std::filesystem::path& model, std::string* why) {
  char dir[] = "/tmp/fabatlas-bounds-XXXXXX";
  if (!::mkdtemp(dir)) {
    *why = "cannot create a temporary directory for openscad";
    return "";
  }
  const std::filesystem::path out = std::filesystem::path(dir) / "model.csg";
  std::string text;
  try {
    OpenScadRun run;
    if (RunOpenScad(model, out, {}, &run)) {
      std::ifstream in(out, std::ios::binary);
      std::stringstream ss;
      ss << in.rdbuf();
      text = ss.str();
    } else {
      *why = "openscad failed: " + run.log_tail;
    }
  } catch (const InputError& e) {
    *why = e.what();
  }
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  return text;
}

}  // namespace

CsgBox ModelBounds(const std::filesystem::path& model) {
  const ModelEvaluation own = EvaluateModel(model, {});
  std::string csg = own.csg, why;
  if (!own.evaluated) csg = OpenScadCsg(model, &why);
  if (csg.empty() && !why.empty()) return Unknown(model, why);
  try {
    CsgBox box = CsgBounds(ParseCsg(csg, model.string() + " (CSG tree)"));
    if (!box.known) box.unknown = model.string() + ": CSG line " + box.unknown;
    return box;
  } catch (const InputError& e) {
    return Unknown(model, e.what());
  }
}

}  // namespace fabatlas::scad
