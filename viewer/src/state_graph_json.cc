// A reconfigurable design's JSON documents: /api/state_graph and
// /api/resolve (Reconfigurables Sec. 5 and 6; docs/viewer.md, "API").
#include <set>

#include "api_json.h"
#include "fabatlas/design/resolution_hint.h"
#include "fabatlas/design/resolve_collisions.h"
#include "fabatlas/design/state_graph.h"
#include "fabatlas/precompute/design_evaluator.h"

namespace fabatlas::viewer {

using nlohmann::json;

// A reconfigurable design at exactly u, to be played (Reconfigurables Sec. 5):
// the design evaluated there with every check (design::EvaluateStateGraph),
// each object's mesh (body frame, mm, z up), and per transition the poses of
// every object at `frames` evenly spaced times plus the ends of every
// collision interval, the intervals (first by when, then where) and the
// first colliding time over all transitions.
json StateGraphJson(const Customiser& c, const std::vector<double>& u, int frames) {
  if (!c.source().design) throw BadRequest{"this form has no design"};
  const design::Design& d = *c.source().design;
  if (d.objects.empty() || d.transitions.empty())
    throw BadRequest{"this design has no state graph (objects and transitions)"};
  const design::StateGraphResult r = design::EvaluateStateGraph(d, precompute::DesignPointOf(d, u));
  const design::StateGraph& g = r.graph;
  json j = {
      {"u", u}, {"valid", r.sample.valid}, {"collisions_checked", g.collisions_checked}, {"time_steps", g.time_steps}};
  if (!r.sample.valid) {
    j["failure"] = r.sample.failure;
    j["reason"] = r.sample.failure_reason;
    for (const auto& check : r.sample.checks)
      if (!check.passed) {
        j["check"] = check.name;
        break;
      }
  }
  json objects = json::array();
  for (std::size_t k = 0; k < g.objects.size(); ++k) {
    json positions = json::array(), triangles = json::array();
    for (const auto& v : g.objects[k].vertices)
      for (double x : v) positions.push_back(std::round(x * 1e4) / 1e4);  // 0.1 micrometre: half the bytes
    for (const auto& t : g.objects[k].triangles)
      for (auto i : t) triangles.push_back(i);
    objects.push_back({{"name", g.object_names.at(k)}, {"positions", positions}, {"triangles", triangles}});
  }
  j["objects"] = objects;
  json transitions = json::array();
  json first = nullptr;
  for (const auto& t : g.transitions) {
    std::set<double> times;
    for (int i = 0; i < frames; ++i) times.insert(static_cast<double>(i) / (frames - 1));
    json collisions = json::array();
    for (const auto& ci : t.collisions) {
      times.insert(ci.t_begin);
      times.insert(ci.t_end);
      const json pair = {g.object_names.at(ci.part_a), g.object_names.at(ci.part_b)};
      collisions.push_back({{"t_begin", ci.t_begin},
                            {"t_end", ci.t_end},
                            {"objects", pair},
                            {"where", {{"min", ci.where.min}, {"max", ci.where.max}}}});
      if (first.is_null() || ci.t_begin < first["t"].get<double>())
        first = {{"transition", t.name}, {"t", ci.t_begin}, {"t_end", ci.t_end}, {"objects", pair}};
    }
    json poses = json::array();  // per time, per object: row-major 3x4 [R | T], mm
    for (const double time : times) {
      json at = json::array();
      for (const auto& motion : t.motions) {
        const swept::Transform f = motion.At(time);
        json m = json::array();
        for (int row = 0; row < 3; ++row) {
          for (int col = 0; col < 3; ++col) m.push_back(f.rotation[row][col]);
          m.push_back(f.translation[row]);
        }
        at.push_back(m);
      }
      poses.push_back(at);
    }
    transitions.push_back({{"name", t.name},
                           {"from", t.from},
                           {"to", t.to},
                           {"times", times},
                           {"poses", poses},
                           {"collisions", collisions}});
  }
  j["transitions"] = transitions;
  j["first_collision"] = first;
  return j;
}

// A reconfigurable's collisions at exactly u resolved (Reconfigurables Secs.
// 6.4–6.6; docs/swept.md "Collision resolution"): per collision interval the
// spacetime contact normal of the selected object (the second of the pair)
// and where to draw it (the centre of the interval's box), per pair the
// hint in the parameters and its step, and the design resolved
// automatically, `u` in the form's dimension order, proved by the design's
// checks (`resolved`).
json ResolveJson(const Customiser& c, const std::vector<double>& u) {
  if (!c.source().design) throw BadRequest{"this form has no design"};
  const design::Design& d = *c.source().design;
  if (d.objects.empty() || d.transitions.empty())
    throw BadRequest{"this design has no state graph (objects and transitions)"};
  const design::Point at = precompute::DesignPointOf(d, u);
  const design::HintSummary h = design::ResolutionHints(d, at);
  json j = {{"u", u}, {"valid", h.sample.valid}, {"failure", h.sample.failure}, {"energy", h.energy}};
  json intervals = json::array();
  for (const auto& i : h.intervals) {
    const auto& n = i.normal;
    swept::Vec3 centre;
    for (int k = 0; k < 3; ++k) centre[k] = 0.5 * (i.where.min[k] + i.where.max[k]);
    intervals.push_back({{"transition", i.transition},
                         {"objects", {i.object_a, i.object_b}},
                         {"object", i.object_b},
                         {"t_begin", i.t_begin},
                         {"t_end", i.t_end},
                         {"at", centre},
                         {"normal", n.spacetime_normal},
                         {"energy", n.energy},
                         {"first_contact_normal", n.has_first_contact ? json(n.first_contact_normal) : json(nullptr)}});
  }
  j["intervals"] = intervals;
  json pairs = json::array();
  for (const auto& p : h.pairs)
    pairs.push_back(
        {{"objects", {p.object_a, p.object_b}}, {"energy", p.energy}, {"descent", p.descent}, {"step", p.step}});
  j["pairs"] = pairs;
  json resolution = nullptr;
  if (!h.sample.valid && !h.intervals.empty()) {
    const design::ResolveSummary r = design::ResolveCollisions(d, at);
    std::vector<double> after;
    for (const auto& e : d.exposed) after.push_back(r.after.at(e.name));
    resolution = {{"resolved", r.resolved},
                  {"u", after},
                  {"edit", r.edit},
                  {"edit_size", r.edit_size},
                  {"failure", r.failure_after},
                  {"steps", r.steps.size()},
                  {"evaluations", r.evaluations}};
  }
  j["resolution"] = resolution;
  return j;
}

}  // namespace fabatlas::viewer
