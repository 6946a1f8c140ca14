// fabatlas/viewer/http_api.h — the customiser's JSON/glTF API, independent of
// the HTTP library so tests call it directly (docs/viewer.md lists the routes).
//
//   GET /api/form                  parameters, materials, starting points, statistics
//   GET /api/params                the parameter schema: exposed and fixed parameters,
//                                  groups, ranges, where valid stretches come from
//   GET /api/intervals?u=a,b,..    validity of u and every dimension's stretches through u
//   GET /api/snap?u=..             the snapped sample and its ΔG-weighted distance
//   GET /api/properties?u=..       the snapped sample's properties and material cost/weight
//   GET /api/preview.glb?u=..      the snapped sample's geometry as glTF binary;
//                                  &exact=1: the design at exactly u when cheap
//                                  enough (Customiser::PreviewGlbAt); an OpenSCAD
//                                  model's parts as nodes with their colours
//   GET /api/map?a=i&b=j&n=N&u=..  N x N validity map over parameters i and j through u
//   GET /api/export?u=..&format=F  the design at exactly u as a file (export_design.h);
//                                  &part=NAME: one part's stl/obj; X-Parts lists them
//   GET /api/optimise?min=P&hold=..   the best valid point for an objective (optimise.h)
//   GET /api/pareto?axes=A,B        the Pareto front of two properties (pareto_front.h)
//
// u lists one value per parameter in the form's order (enumerated: the value
// index). Bad requests (unparsable or non-finite numbers, wrong arity, a value
// outside its range, a point outside the valid region for an export, unknown
// route) answer 400/404 with a one-line reason; any other exception is a 500
// with its reason. Never throws.
#pragma once

#include <map>
#include <memory>
#include <string>

#include "fabatlas/viewer/customiser.h"

namespace fabatlas::viewer {

struct ApiResponse {
  int status = 200;
  std::string content_type = "application/json";
  std::string body;
  // When set, the body instead of `body`, shared rather than copied (a
  // cached preview).
  std::shared_ptr<const std::string> shared_body;
  std::map<std::string, std::string> headers;

  const std::string& bytes() const { return shared_body ? *shared_body : body; }
};

// path: the request path ("/api/..."); query: decoded query parameters.
ApiResponse HandleApiRequest(const Customiser& customiser, const std::string& path,
                             const std::map<std::string, std::string>& query);

// The routes that also take POST (/api/optimise, /api/pareto): true for them.
bool AcceptsPost(const std::string& path);

// A POST to /api/optimise or /api/pareto: `body` is a JSON object whose keys
// are the GET route's query parameters; a value is a string or number as in
// the query, an object {"name": value, ...} standing for "name=value,..."
// (hold, weights), or an array standing for its items joined by commas. A
// body that is not such an object is a 400 with one line. Never throws.
ApiResponse HandleApiPost(const Customiser& customiser, const std::string& path, const std::string& body);

}  // namespace fabatlas::viewer
