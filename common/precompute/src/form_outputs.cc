#include "fabatlas/precompute/form_outputs.h"

#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/sampling/form_json.h"
#include "fabatlas/sampling/validity_map.h"

namespace fabatlas::precompute {

std::string Table3Row(const design::Design& design, const sampling::SamplingStatistics& s) {
  std::ostringstream out;
  out << design.name << "  |U|=" << design.exposed.size() << "  samples " << s.samples << "  CPU " << std::fixed
      << std::setprecision(1) << s.evaluator_cpu_seconds << " s  valid " << std::setprecision(1)
      << s.valid_volume_percent << "%  failures: ";
  if (s.failure_shares.empty()) out << "none";
  bool first = true;
  for (const auto& [type, share] : s.failure_shares) {
    out << (first ? "" : ", ") << std::setprecision(0) << 100 * share << "% " << type;
    first = false;
  }
  return out.str();
}

bool WritesFormJson(const sampling::JobFile& job, std::size_t samples) {
  return job.form_json.value_or(samples <= kFormJsonMaxSamples);
}

void WriteFormOutputs(const design::Design& design, const sampling::SamplingSummary& summary,
                      const std::filesystem::path& out_dir, bool form_json) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) throw InputError(out_dir.string() + ": cannot create output directory: " + ec.message());
  if (form_json)
    WriteFileAtomically(out_dir / "form.json", sampling::FormToJson(summary.form));
  else
    std::filesystem::remove(out_dir / "form.json", ec);

  const auto& s = summary.statistics;
  nlohmann::json stats{{"design", design.name},
                       {"exposed_parameters", design.exposed.size()},
                       {"samples", s.samples},
                       {"valid_samples", s.valid_samples},
                       {"leaves", s.leaves},
                       {"geometry_changes", s.geometry_changes},
                       {"evaluator_cpu_seconds", s.evaluator_cpu_seconds},
                       {"evaluator_wall_seconds", s.evaluator_wall_seconds},
                       {"wall_seconds", s.wall_seconds},
                       {"sampling_logic_seconds", s.sampling_logic_seconds},
                       {"valid_volume_percent", s.valid_volume_percent},
                       {"failure_shares", s.failure_shares}};
  WriteFileAtomically(out_dir / "statistics.json", stats.dump(2) + "\n");

  std::vector<double> defaults;
  for (const auto& p : design.exposed) defaults.push_back(p.default_value);
  for (std::size_t i = 0; i + 1 < design.exposed.size(); ++i) {
    sampling::ValidityMapOptions options;
    options.x_dimension = static_cast<int>(i);
    options.y_dimension = static_cast<int>(i + 1);
    options.fixed = defaults;
    std::filesystem::path png = out_dir / ("map_" + design.exposed[i].name + "_" + design.exposed[i + 1].name + ".png");
    sampling::WriteValidityMap(summary.form, options, png.string());
  }
}

}  // namespace fabatlas::precompute
