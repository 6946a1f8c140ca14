#include "fabatlas/sampling/form_json.h"

#include <nlohmann/json.hpp>

#include "fabatlas/error.h"

namespace fabatlas::sampling {

namespace {
using nlohmann::json;

const char* StopName(LeafStop s) {
  switch (s) {
    case LeafStop::kNone:
      return "none";
    case LeafStop::kThreshold:
      return "threshold";
    case LeafStop::kMaxDepth:
      return "max_depth";
    case LeafStop::kUnsplittable:
      return "unsplittable";
    case LeafStop::kBudget:
      return "budget";
  }
  return "none";
}

LeafStop StopFromName(const std::string& s) {
  for (LeafStop v :
       {LeafStop::kNone, LeafStop::kThreshold, LeafStop::kMaxDepth, LeafStop::kUnsplittable, LeafStop::kBudget})
    if (s == StopName(v)) return v;
  throw std::runtime_error("unknown leaf stop '" + s + "'");
}
}  // namespace

std::string FormToJson(const Form& form, bool include_timings) {
  json j;
  j["format"] = "fabatlas.form/1";
  j["subdivisions"] = form.subdivisions;
  json dims = json::array();
  for (const Dimension& d : form.dimensions) {
    json jd{{"name", d.name}, {"kind", DimensionKindName(d.kind)}, {"lo", d.lo}, {"hi", d.hi}};
    if (d.kind == DimensionKind::kEnumerated) jd["values"] = d.values;
    dims.push_back(std::move(jd));
  }
  j["dimensions"] = std::move(dims);
  json samples = json::array();
  for (const FormSample& s : form.samples) {
    json js{{"key", s.key},
            {"u", s.u},
            {"valid", s.outcome.valid},
            {"failure", s.outcome.failure_type},
            {"properties", s.outcome.properties}};
    if (include_timings) js["cpu_seconds"] = s.outcome.cpu_seconds;
    samples.push_back(std::move(js));
  }
  j["samples"] = std::move(samples);
  json trees = json::array();
  for (const FormTree& t : form.trees) {
    json nodes = json::array();
    for (const FormNode& n : t.nodes) {
      json jn{{"lo", n.lo}, {"hi", n.hi}, {"depth", n.depth}};
      if (n.split_dimension >= 0) {
        jn["split_dimension"] = n.split_dimension;
        jn["split_key"] = n.split_key;
        jn["children"] = {n.children[0], n.children[1]};
      } else {
        jn["stop"] = StopName(n.stop);
      }
      nodes.push_back(std::move(jn));
    }
    trees.push_back(json{{"cell", t.cell}, {"nodes", std::move(nodes)}});
  }
  j["trees"] = std::move(trees);
  json changes = json::array();
  for (const auto& [edge, dg] : form.geometry_changes) changes.push_back(json::array({edge.first, edge.second, dg}));
  j["geometry_changes"] = std::move(changes);
  return j.dump(1) + "\n";
}

Form FormFromJson(const std::string& text, const std::string& source) {
  try {
    const json j = json::parse(text);
    if (j.at("format").get<std::string>() != "fabatlas.form/1")
      throw std::runtime_error("unsupported format '" + j.at("format").get<std::string>() + "'");
    Form form;
    form.subdivisions = j.at("subdivisions").get<int>();
    for (const json& jd : j.at("dimensions")) {
      Dimension d;
      d.name = jd.at("name").get<std::string>();
      const std::string kind = jd.at("kind").get<std::string>();
      if (!DimensionKindFromName(kind, &d.kind)) throw std::runtime_error("unknown dimension kind '" + kind + "'");
      d.lo = jd.at("lo").get<double>();
      d.hi = jd.at("hi").get<double>();
      if (jd.contains("values")) d.values = jd.at("values").get<std::vector<std::string>>();
      form.dimensions.push_back(std::move(d));
    }
    const size_t n = form.dimensions.size();
    for (const json& js : j.at("samples")) {
      FormSample s;
      s.key = js.at("key").get<PointKey>();
      s.u = js.at("u").get<std::vector<double>>();
      if (s.key.size() != n || s.u.size() != n) throw std::runtime_error("sample of wrong dimension");
      s.outcome.valid = js.at("valid").get<bool>();
      s.outcome.failure_type = js.at("failure").get<std::string>();
      s.outcome.properties = js.at("properties").get<std::map<std::string, double>>();
      if (js.contains("cpu_seconds")) s.outcome.cpu_seconds = js.at("cpu_seconds").get<double>();
      if (!form.sample_ids.emplace(s.key, static_cast<std::int64_t>(form.samples.size())).second)
        throw std::runtime_error("duplicate sample key");
      form.samples.push_back(std::move(s));
    }
    for (const json& jt : j.at("trees")) {
      FormTree t;
      t.cell = jt.at("cell").get<std::vector<int>>();
      for (const json& jn : jt.at("nodes")) {
        FormNode node;
        node.lo = jn.at("lo").get<std::vector<std::int64_t>>();
        node.hi = jn.at("hi").get<std::vector<std::int64_t>>();
        node.depth = jn.at("depth").get<int>();
        if (jn.contains("split_dimension")) {
          node.split_dimension = jn.at("split_dimension").get<int>();
          node.split_key = jn.at("split_key").get<std::int64_t>();
          node.children[0] = jn.at("children").at(0).get<int>();
          node.children[1] = jn.at("children").at(1).get<int>();
        } else {
          node.stop = StopFromName(jn.at("stop").get<std::string>());
        }
        t.nodes.push_back(std::move(node));
      }
      for (const FormNode& node : t.nodes) {
        if (node.lo.size() != n || node.hi.size() != n) throw std::runtime_error("node of wrong dimension");
        if (node.split_dimension >= 0) {
          for (int c : node.children)
            if (c <= 0 || c >= static_cast<int>(t.nodes.size())) throw std::runtime_error("child index out of range");
        } else {
          CornerSampleIds(form, node);  // throws std::out_of_range if a corner has no sample
        }
      }
      form.trees.push_back(std::move(t));
    }
    for (const json& jc : j.at("geometry_changes")) {
      const auto a = jc.at(0).get<std::int64_t>(), b = jc.at(1).get<std::int64_t>();
      if (a < 0 || b < 0 || a >= static_cast<std::int64_t>(form.samples.size()) ||
          b >= static_cast<std::int64_t>(form.samples.size()))
        throw std::runtime_error("ΔG refers to an unknown sample");
      form.geometry_changes[{a, b}] = jc.at(2).get<double>();
    }
    form.space();  // validates the dimensions
    return form;
  } catch (const InputError& e) {
    throw InputError(source + ": " + e.what());
  } catch (const std::exception& e) {
    throw InputError(source + ": " + e.what());
  }
}

}  // namespace fabatlas::sampling
