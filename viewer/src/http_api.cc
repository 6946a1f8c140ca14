#include "fabatlas/viewer/http_api.h"

#include <charconv>
#include <cmath>
#include <optional>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "api_json.h"
#include "fabatlas/error.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/artifact/glb.h"
#include "fabatlas/viewer/export_design.h"
#include "fabatlas/viewer/failure_reason.h"
#include "fabatlas/viewer/optimise.h"
#include "fabatlas/viewer/pareto_front.h"
#include "fabatlas/viewer/property_limits.h"

namespace fabatlas::viewer {

namespace {

using nlohmann::json;

double ParseNumber(const std::string& text, const std::string& what) {
  double v = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, v);
  if (text.empty() || ec != std::errc() || ptr != end) throw BadRequest{what + ": '" + text + "' is not a number"};
  if (!std::isfinite(v)) throw BadRequest{what + ": " + text + " is not finite"};
  return v;
}

int ParseIndex(const std::map<std::string, std::string>& query, const std::string& name, int lo, int hi, int fallback) {
  const auto it = query.find(name);
  if (it == query.end()) {
    if (fallback >= lo) return fallback;
    throw BadRequest{"missing query parameter '" + name + "'"};
  }
  const double v = ParseNumber(it->second, name);
  if (v != std::floor(v) || v < lo || v > hi)
    throw BadRequest{name + " must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                     it->second};
  return static_cast<int>(v);
}

// u: one value per dimension, inside its range.
std::vector<double> ParsePoint(const Customiser& c, const std::map<std::string, std::string>& query) {
  const auto it = query.find("u");
  if (it == query.end()) throw BadRequest{"missing query parameter 'u' (one value per parameter, comma-separated)"};
  std::vector<double> u;
  std::string item;
  std::istringstream in(it->second);
  while (std::getline(in, item, ',')) u.push_back(ParseNumber(item, "u[" + std::to_string(u.size()) + "]"));
  if (!it->second.empty() && it->second.back() == ',') throw BadRequest{"u ends with a comma"};
  const int n = c.dimension_count();
  if (static_cast<int>(u.size()) != n)
    throw BadRequest{"u has " + std::to_string(u.size()) + " values, the form has " + std::to_string(n) +
                     " parameters"};
  for (int d = 0; d < n; ++d) {
    const auto& dim = c.space().dimension(d);
    const double lo = c.space().value(d, c.space().key_lo(d)), hi = c.space().value(d, c.space().key_hi(d));
    if (u[d] < lo || u[d] > hi) {
      std::ostringstream msg;
      msg << "u[" << d << "] = " << u[d] << " is outside " << dim.name << "'s range [" << lo << ", " << hi << "]";
      throw BadRequest{msg.str()};
    }
  }
  return u;
}

ApiResponse Json(const json& j) {
  ApiResponse r;
  r.body = j.dump();
  return r;
}

std::vector<PropertyLimit> LimitsOf(const Customiser& c, const std::map<std::string, std::string>& query) {
  const auto it = query.find("limits");
  if (it == query.end()) return {};
  try {
    return ParseLimits(it->second, c.source().materials);
  } catch (const InputError& e) {
    throw BadRequest{e.what()};
  }
}

// One GET request to a route that looks at the form: the customiser, the query
// and the form as the user's limits (if any) leave it.
struct FormRequest {
  const Customiser& c;
  const std::map<std::string, std::string>& query;
  const std::vector<PropertyLimit>& limits;
  const sampling::Form& form;

  // The valid sample nearest u in the limited form; a 400 when there is none.
  std::int64_t SnappedSample(const std::vector<double>& u) const {
    const auto snap = SnapToValidSample(form, c.space(), u);
    if (!snap)
      throw BadRequest{limits.empty() ? "the form has no valid sample to snap to"
                                      : "no valid sample meets your limits"};
    return snap->sample;
  }
};

ApiResponse IntervalsRoute(const FormRequest& r) {
  const Customiser& c = r.c;
  const auto u = ParsePoint(c, r.query);
  json dims = json::array();
  for (int d = 0; d < c.dimension_count(); ++d)
    dims.push_back(StretchesJson(LineStretches(r.form, c.space(), c.corners(), u, d)));
  const bool valid = IsValidPoint(r.form, c.space(), c.corners(), u);
  json j = {{"u", u}, {"valid", valid}, {"dimensions", dims}};
  if (!valid) j["failures"] = FailuresAt(r.form, c.space(), c.corners(), u);
  return Json(j);
}

ApiResponse ReasonRoute(const FormRequest& r) {
  const auto u = ParsePoint(r.c, r.query);
  const auto reason = ReasonAt(r.c, r.form, r.limits, u);
  if (!reason) return Json({{"u", u}, {"sample", -1}});
  return Json({{"u", u},
               {"sample", reason->sample},
               {"sample_u", reason->u},
               {"check", reason->check},
               {"failure", reason->failure},
               {"reason", reason->reason}});
}

ApiResponse SnapRoute(const FormRequest& r) {
  const Customiser& c = r.c;
  const auto u = ParsePoint(c, r.query);
  const auto snap = SnapToValidSample(r.form, c.space(), u);
  if (!snap) r.SnappedSample(u);  // throws the 400 that names why
  return Json({{"u", u},
               {"sample", snap->sample},
               {"sample_u", c.form().samples[snap->sample].u},
               {"distance", snap->distance},
               {"inside_leaf", snap->inside_leaf}});
}

ApiResponse PropertiesRoute(const FormRequest& r) {
  const auto u = ParsePoint(r.c, r.query);
  return Json(SampleJson(r.c, r.SnappedSample(u)));
}

// The shortest text that reads back as the same doubles, comma-separated.
std::string ShortestText(const std::vector<double>& u) {
  std::string shown;
  for (std::size_t d = 0; d < u.size(); ++d) {
    char text[32];
    shown += std::string(d ? "," : "") + std::string(text, std::to_chars(text, text + sizeof text, u[d]).ptr);
  }
  return shown;
}

ApiResponse PreviewRoute(const FormRequest& r) {
  const Customiser& c = r.c;
  const auto u = ParsePoint(c, r.query);
  if (!c.source().design) throw BadRequest{"this form has no design to preview"};
  const auto e = r.query.find("exact");
  if (e != r.query.end() && e->second != "0" && e->second != "1")
    throw BadRequest{"exact must be 0 or 1, got '" + e->second + "'"};
  const bool asked = e != r.query.end() && e->second == "1";
  // Only a point the (limited) form calls valid is shown exactly; the
  // page's validity stays the form's (docs/viewer.md, Exact previews).
  const bool inside = asked && IsValidPoint(r.form, c.space(), c.corners(), u);
  PointPreview p = c.PreviewGlbAt(u, r.SnappedSample(u), inside);
  if (asked && !inside) p.fallback = "outside";
  ApiResponse response;
  response.content_type = "model/gltf-binary";
  response.shared_body = std::shared_ptr<const std::string>(p.preview, &p.preview->glb);
  auto& headers = response.headers;
  headers["X-Sample"] = std::to_string(p.sample);
  headers["X-Preview"] = p.exact ? "exact" : "snapped";
  headers["X-Preview-U"] = ShortestText(p.u);
  headers["X-Preview-Seconds"] = std::to_string(p.seconds);
  headers["X-Preview-Estimate"] = std::to_string(p.estimate_seconds);
  if (!p.fallback.empty()) headers["X-Preview-Fallback"] = p.fallback;
  headers["X-Cache-Hits"] = std::to_string(p.preview->cache_hits) + "/" + std::to_string(p.preview->subtrees);
  headers["X-Preview-Cache"] = p.exact ? "none" : p.cache_hit ? "hit" : "miss";
  return response;
}

// names joined by commas, "" for none.
std::string CommaList(const std::vector<std::string>& names) {
  std::string list;
  for (const auto& name : names) list += (list.empty() ? "" : ",") + name;
  return list;
}

ApiResponse ExportRoute(const FormRequest& r) {
  const auto u = ParsePoint(r.c, r.query);
  ExportOptions options;
  const auto f = r.query.find("format");
  options.format = f == r.query.end() ? "stl" : f->second;
  if (const auto part = r.query.find("part"); part != r.query.end()) options.part = part->second;
  const ExportResult e = ExportDesign(r.c, u, options);
  ApiResponse response;
  response.content_type = options.format == "glb"   ? "model/gltf-binary"
                          : options.format == "3mf" ? "model/3mf"
                          : options.format == "stl" ? "model/stl"
                                                    : "model/obj";
  response.body = e.bytes;
  response.headers["Content-Disposition"] = "attachment; filename=\"" + e.file_name + "\"";
  response.headers["X-Voxel-Size"] = std::to_string(e.voxel_size);
  response.headers["X-Triangles"] = std::to_string(e.triangles);
  response.headers["X-Checks"] = CommaList(e.checks);  // the checks passed at exactly u
  response.headers["X-Parts"] = CommaList(e.parts);    // every part at u, "name" or "name #rrggbb"
  return response;
}

ApiResponse StateGraphRoute(const FormRequest& r) {
  const int frames = ParseIndex(r.query, "frames", 2, 1000, 61);
  return Json(StateGraphJson(r.c, ParsePoint(r.c, r.query), frames));
}

ApiResponse ResolveRoute(const FormRequest& r) { return Json(ResolveJson(r.c, ParsePoint(r.c, r.query))); }

ApiResponse MapRoute(const FormRequest& r) {
  const Customiser& c = r.c;
  const int n_dims = c.dimension_count();
  const int a = ParseIndex(r.query, "a", 0, n_dims - 1, -1), b = ParseIndex(r.query, "b", 0, n_dims - 1, -1);
  if (a == b) throw BadRequest{"a and b must name two different parameters"};
  const int n = ParseIndex(r.query, "n", 2, 256, 64);
  const auto u = ParsePoint(c, r.query);
  const auto& space = c.space();
  const double alo = space.value(a, space.key_lo(a)), ahi = space.value(a, space.key_hi(a));
  const double blo = space.value(b, space.key_lo(b)), bhi = space.value(b, space.key_hi(b));
  std::vector<std::string> failure_names;
  std::map<std::string, int> failure_index;
  json cells = json::array();  // row-major, row 0 = lowest b; -1 valid, else failure index
  std::vector<double> p = u;
  for (int j = 0; j < n; ++j) {
    p[b] = blo + (bhi - blo) * (j + 0.5) / n;
    for (int i = 0; i < n; ++i) {
      p[a] = alo + (ahi - alo) * (i + 0.5) / n;
      if (IsValidPoint(r.form, c.space(), c.corners(), p)) {
        cells.push_back(-1);
        continue;
      }
      const auto f = FailuresAt(r.form, c.space(), c.corners(), p);
      const std::string name = f.empty() ? "invalid" : f.front();
      auto [it, inserted] = failure_index.insert({name, static_cast<int>(failure_names.size())});
      if (inserted) failure_names.push_back(name);
      cells.push_back(it->second);
    }
  }
  return Json({{"a", a},
               {"b", b},
               {"n", n},
               {"a_range", {alo, ahi}},
               {"b_range", {blo, bhi}},
               {"failures", failure_names},
               {"cells", cells}});
}

ApiResponse OptimiseRoute(const FormRequest& r) {
  const Customiser& c = r.c;
  const auto& query = r.query;
  // The objective: min=P or max=P (P a property, or weights a=1,b=2), or
  // weights=a=1,b=2 (minimised).
  const auto min = query.find("min"), max = query.find("max"), weights = query.find("weights");
  const int given = (min != query.end()) + (max != query.end()) + (weights != query.end());
  if (given != 1) throw BadRequest{"name exactly one objective: min=PROPERTY, max=PROPERTY or weights=a=1,b=2"};
  OptimiseOptions options;
  options.maximise = max != query.end();
  options.terms = ParseObjective((min != query.end() ? min : max != query.end() ? max : weights)->second);
  const auto hold = query.find("hold");
  if (hold != query.end()) options.hold = ParseHolds(hold->second, c.space());
  const OptimiseResult o = Optimise(r.form, c.corners(), c.source().materials, options);
  if (!o.found)
    return Json({{"found", false},
                 {"reason", r.limits.empty() ? "no valid point on the held values"
                                             : "no valid point meets your limits on the held values"}});
  json values = json::object();
  for (std::size_t k = 0; k < o.values.size(); ++k) values[o.properties[k]] = o.values[k];
  return Json({{"found", true},
               {"u", o.u},
               {"objective", o.objective},
               {"maximise", options.maximise},
               {"values", values},
               {"sample", o.sample},
               {"interpolated", o.sample < 0},
               {"corners", o.corners},
               {"candidates", o.candidates},
               {"valid", IsValidPoint(r.form, c.space(), c.corners(), o.u)}});
}

ApiResponse ParetoRoute(const FormRequest& r) {
  const auto axes = r.query.find("axes");
  if (axes == r.query.end()) throw BadRequest{"missing query parameter 'axes' (A,B; each optionally min: or max:)"};
  ParetoOptions options = ParseParetoAxes(axes->second);
  const int dominated = ParseIndex(r.query, "dominated", 0, 100000, 0);  // at most this many, evenly spread
  options.keep_dominated = dominated > 0;
  const ParetoFront front = ParetoFrontOf(r.form, r.c.source().materials, options);
  json points = json::array(), others = json::array();
  for (const auto& p : front.points)
    points.push_back(
        {{"sample", p.sample}, {"u", r.form.samples[static_cast<std::size_t>(p.sample)].u}, {"a", p.a}, {"b", p.b}});
  const std::size_t stride = dominated > 0 ? (front.dominated.size() + dominated - 1) / dominated : 1;
  for (std::size_t k = 0; k < front.dominated.size(); k += std::max<std::size_t>(stride, 1))
    others.push_back({{"sample", front.dominated[k].sample}, {"a", front.dominated[k].a}, {"b", front.dominated[k].b}});
  return Json({{"a", front.a},
               {"b", front.b},
               {"a_maximise", options.a.maximise},
               {"b_maximise", options.b.maximise},
               {"points", points},
               {"dominated", others},
               {"dominated_total", front.dominated.size()},
               {"candidates", front.candidates}});
}

// Every GET route that looks at the form, by path.
const std::map<std::string, ApiResponse (*)(const FormRequest&)>& FormRoutes() {
  static const std::map<std::string, ApiResponse (*)(const FormRequest&)> routes = {
      {"/api/intervals", IntervalsRoute},     // valid stretches along each parameter through u
      {"/api/reason", ReasonRoute},           // why u is invalid, in words
      {"/api/snap", SnapRoute},               // the valid sample u snaps to
      {"/api/properties", PropertiesRoute},   // that sample's properties
      {"/api/preview.glb", PreviewRoute},     // the preview mesh at u (exact or snapped)
      {"/api/export", ExportRoute},           // the design at exactly u as a file
      {"/api/state_graph", StateGraphRoute},  // a reconfigurable at exactly u, to play
      {"/api/resolve", ResolveRoute},         // a reconfigurable's collisions at u resolved
      {"/api/map", MapRoute},                 // validity over a grid of two parameters
      {"/api/optimise", OptimiseRoute},       // the best valid point for an objective
      {"/api/pareto", ParetoRoute},           // the trade-off between two properties
  };
  return routes;
}

ApiResponse Route(const Customiser& c, const std::string& path, const std::map<std::string, std::string>& query) {
  if (path == "/api/form") return Json(FormJson(c));
  if (path == "/api/params") return Json(ParamsJson(c));
  // Every lookup below sees the form under the user's limits, if any (even a
  // path that names no route, whose limits still answer 400 when malformed).
  const std::vector<PropertyLimit> limits = LimitsOf(c, query);
  const std::shared_ptr<const sampling::Form> shown = c.LimitedForm(limits);
  const auto route = FormRoutes().find(path);
  if (route != FormRoutes().end()) return route->second(FormRequest{c, query, limits, *shown});
  ApiResponse r;
  r.status = 404;
  r.content_type = "text/plain; charset=utf-8";
  r.body = "no such API route: " + path + "\n";
  return r;
}

}  // namespace

ApiResponse HandleApiRequest(const Customiser& c, const std::string& path,
                             const std::map<std::string, std::string>& query) {
  try {
    return Route(c, path, query);
  } catch (const BadRequest& e) {
    ApiResponse r;
    r.status = 400;
    r.content_type = "text/plain; charset=utf-8";
    r.body = e.reason + "\n";
    return r;
  } catch (const InputError& e) {
    ApiResponse r;
    r.status = 400;
    r.content_type = "text/plain; charset=utf-8";
    r.body = std::string(e.what()) + "\n";
    return r;
  } catch (const std::exception& e) {
    // A fault of ours, not of the request: answered, never a dropped connection.
    ApiResponse r;
    r.status = 500;
    r.content_type = "text/plain; charset=utf-8";
    r.body = std::string("internal error: ") + e.what() + "\n";
    return r;
  }
}

bool AcceptsPost(const std::string& path) { return path == "/api/optimise" || path == "/api/pareto"; }

ApiResponse HandleApiPost(const Customiser& c, const std::string& path, const std::string& body) {
  std::map<std::string, std::string> query;
  const auto bad = [](const std::string& reason, int status = 400) {
    ApiResponse r;
    r.status = status;
    r.content_type = "text/plain";
    r.body = reason + "\n";
    return r;
  };
  const auto text = [](const json& v) -> std::optional<std::string> {
    if (v.is_string()) return v.get<std::string>();
    if (v.is_number()) return v.dump();
    return std::nullopt;
  };
  if (!AcceptsPost(path)) {
    ApiResponse r = bad("POST is not allowed here; only /api/optimise and /api/pareto take POST", 405);
    r.headers["Allow"] = "GET";
    return r;
  }
  const json j = json::parse(body, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return bad("the request body is not a JSON object");
  for (const auto& [key, value] : j.items()) {
    std::string joined;
    if (value.is_object() || value.is_array()) {
      for (const auto& [name, item] : value.items()) {
        const auto t = text(item);
        if (!t) return bad("'" + key + "': items must be strings or numbers");
        joined += (joined.empty() ? "" : ",") + (value.is_object() ? name + "=" : std::string()) + *t;
      }
    } else if (const auto t = text(value)) {
      joined = *t;
    } else {
      return bad("'" + key + "': expected a string, a number, an object or an array");
    }
    query[key] = joined;
  }
  return HandleApiRequest(c, path, query);
}

}  // namespace fabatlas::viewer
