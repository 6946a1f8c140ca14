#include "sample_report.h"

#include <iomanip>
#include <sstream>

namespace fabatlas::cli {

namespace {
nlohmann::json PointJson(const design::Design& d, const design::Point& u) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& p : d.exposed) {
    double v = u.at(p.name);
    if (p.kind == design::ParameterKind::kEnumerated)
      j[p.name] = p.labels.at(static_cast<std::size_t>(v));
    else
      j[p.name] = v;
  }
  return j;
}
}  // namespace

nlohmann::json SampleJson(const design::Design& d, const design::SampleResult& r) {
  nlohmann::json j;
  j["design"] = d.name;
  j["point"] = PointJson(d, r.u);
  j["valid"] = r.valid;
  j["failure"] = r.valid ? nlohmann::json(nullptr) : nlohmann::json(r.failure);
  if (!r.valid) j["failure_reason"] = r.failure_reason;
  j["checks"] = nlohmann::json::object();
  for (const auto& c : r.checks) {
    nlohmann::json cj{{"passed", c.passed}, {"reason", c.reason}, {"seconds", c.seconds}};
    if (!c.passed) cj["failure"] = c.failure;
    if (!c.measures.empty()) cj["measures"] = c.measures;  // e.g. collision_t_begin, full precision
    j["checks"][c.name] = cj;
  }
  j["properties"] = r.properties;
  j["values"] = r.values;
  j["timings"] = r.timings;
  nlohmann::json subtrees = nlohmann::json::array();
  for (const auto& s : r.subtrees)
    subtrees.push_back({{"path", s.path},
                        {"op", s.op},
                        {"key", s.key},
                        {"topology", s.topology},
                        {"seconds", s.seconds},
                        {"from_cache", s.from_cache},
                        {"bytes", s.bytes}});
  j["subtrees"] = subtrees;
  j["warnings"] = r.warnings;
  return j;
}

std::string SampleText(const design::Design& d, const design::SampleResult& r) {
  std::ostringstream out;
  out << d.name << " at " << PointJson(d, r.u).dump() << ": " << (r.valid ? "VALID" : "INVALID (" + r.failure + ")")
      << "\n";
  for (const auto& c : r.checks) {
    out << "  " << std::left << std::setw(16) << c.name << (c.passed ? "pass" : "FAIL");
    if (!c.reason.empty()) out << "  " << c.reason;
    out << "\n";
  }
  for (const auto& [name, value] : r.properties) out << "  " << std::left << std::setw(16) << name << value << "\n";
  for (const auto& w : r.warnings) out << "  warning: " << w << "\n";
  out << "  " << std::left << std::setw(16) << "time" << std::fixed << std::setprecision(3) << r.timings.at("total")
      << " s\n";
  return out.str();
}

}  // namespace fabatlas::cli
