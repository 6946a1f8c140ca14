// The form's JSON documents: /api/form, /api/params, a sample's properties
// and the valid stretches (docs/viewer.md, "API").
#include <set>

#include "api_json.h"

namespace fabatlas::viewer {

using nlohmann::json;

json SampleJson(const Customiser& c, std::int64_t id) {
  const auto& s = c.form().samples.at(id);
  json properties = json::object();
  for (const auto& [name, value] : s.outcome.properties) properties[name] = value;
  json materials = json::array();
  for (const auto& m : c.Materials(id))
    materials.push_back({{"name", m.name}, {"weight_g", m.weight_g}, {"cost", m.cost}});
  return {{"sample", id}, {"u", s.u}, {"valid", s.outcome.valid}, {"properties", properties}, {"materials", materials}};
}

// The design's fixed parameters (design.h FixedParameter), in file order.
json FixedJson(const Customiser& c) {
  json fixed = json::array();
  if (!c.source().design) return fixed;
  for (const auto& f : c.source().design->fixed) {
    json j = {{"name", f.name}, {"value", f.value}};
    if (!f.group.empty()) j["group"] = f.group;
    if (!f.description.empty()) j["description"] = f.description;
    if (!f.why.empty()) j["why"] = f.why;
    fixed.push_back(j);
  }
  return fixed;
}

// The parameter schema for other front ends (docs/viewer.md, "Parameter
// schema"): every parameter of the form, exposed ones with their ranges and
// fixed ones with their values, the groups, and where valid stretches come from.
json ParamsJson(const Customiser& c) {
  json params = json::array();
  json groups = json::array();
  auto add_group = [&](const std::string& g) {
    if (std::find(groups.begin(), groups.end(), json(g)) == groups.end()) groups.push_back(g);
  };
  for (int d = 0; d < c.dimension_count(); ++d) {
    const auto& dim = c.space().dimension(d);
    json j = {{"name", dim.name},
              {"exposed", true},
              {"dimension", d},
              {"kind", sampling::DimensionKindName(dim.kind)},
              {"min", c.space().value(d, c.space().key_lo(d))},
              {"max", c.space().value(d, c.space().key_hi(d))},
              // Continuous for real parameters; whole steps otherwise.
              {"step", dim.kind == sampling::DimensionKind::kReal ? json(nullptr) : json(1)}};
    if (dim.kind == sampling::DimensionKind::kEnumerated) j["values"] = dim.values;
    std::string group;
    if (c.source().design) {
      const auto& e = c.source().design->exposed.at(d);
      j["default"] = e.default_value;
      if (!e.description.empty()) j["description"] = e.description;
      group = e.group;
    }
    j["group"] = group;
    add_group(group);
    params.push_back(j);
  }
  for (json f : FixedJson(c)) {
    f["exposed"] = false;
    if (!f.contains("group")) f["group"] = "";
    add_group(f["group"].get<std::string>());
    params.push_back(f);
  }
  return {{"name", c.source().name},
          {"parameters", params},
          {"groups", groups},
          {"valid_stretches",
           {{"route", "/api/intervals"},
            {"query", "u=<one value per exposed parameter, in dimension order; enumerated by index>[&limits=...]"},
            {"answer",
             "per exposed parameter, the valid and invalid stretches [{lo, hi, valid, failures}] along it through u"},
            {"source", "the form's k-d cells and their sampled corners (Fab Forms Sec. 7.2)"}}}};
}

json FormJson(const Customiser& c) {
  json dims = json::array();
  for (int d = 0; d < c.dimension_count(); ++d) {
    const auto& dim = c.space().dimension(d);
    json j = {{"name", dim.name},
              {"kind", sampling::DimensionKindName(dim.kind)},
              {"lo", c.space().value(d, c.space().key_lo(d))},
              {"hi", c.space().value(d, c.space().key_hi(d))}};
    if (dim.kind == sampling::DimensionKind::kEnumerated) j["values"] = dim.values;
    if (c.source().design) {
      const auto& e = c.source().design->exposed.at(d);
      j["default"] = e.default_value;
      if (!e.description.empty()) j["description"] = e.description;
      if (!e.group.empty()) j["group"] = e.group;
    }
    dims.push_back(j);
  }
  json starts = json::array();
  for (std::int64_t id : c.starting_points()) starts.push_back(SampleJson(c, id));
  json materials = json::array();
  for (const auto& m : c.source().materials)
    materials.push_back(
        {{"name", m.name}, {"density_g_per_cm3", m.density_g_per_cm3}, {"price_per_kg", m.price_per_kg}});
  std::int64_t valid = 0;
  std::set<std::string> property_names;  // what limits can bound
  for (const auto& s : c.form().samples) {
    valid += s.outcome.valid;
    if (s.outcome.valid)
      for (const auto& [name, value] : s.outcome.properties) property_names.insert(name);
  }
  // Reconfigurables: the state graph the page can play (/api/state_graph).
  json states = json::array(), transitions = json::array(), objects = json::array();
  if (c.source().design) {
    const design::Design& d = *c.source().design;
    for (const auto& o : d.objects) objects.push_back(o.name);
    states = d.states;
    for (const auto& t : d.transitions) transitions.push_back({{"name", t.name}, {"from", t.from}, {"to", t.to}});
  }
  return {{"name", c.source().name},
          {"objects", objects},
          {"states", states},
          {"transitions", transitions},
          {"dimensions", dims},
          {"fixed", FixedJson(c)},
          {"materials", materials},
          {"starting_points", starts},
          {"samples", c.form().samples.size()},
          {"valid_samples", valid},
          {"properties", property_names},
          {"cache", c.source().cache_name},
          {"preview", c.source().design.has_value()}};
}

json StretchesJson(const std::vector<Stretch>& stretches) {
  json out = json::array();
  for (const Stretch& s : stretches) {
    json j = {{"lo", s.lo}, {"hi", s.hi}, {"valid", s.valid}};
    if (!s.valid) j["failures"] = s.failures;
    out.push_back(j);
  }
  return out;
}

}  // namespace fabatlas::viewer
