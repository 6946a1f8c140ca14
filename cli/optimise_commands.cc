// fabatlas optimise ART (--min P | --max P | --weights a=1,b=2) [--hold name=v]
//   [--limits L] [--json] — the best valid design for an objective
//   (viewer/optimise.h, docs/viewer.md "Objectives and trade-offs").
// fabatlas inspect ART --pareto A,B writes the Pareto front of two properties
// as CSV and PNG (ParetoCommand below, registered by inspect).
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "commands.h"
#include "fabatlas/error.h"
#include "fabatlas/viewer/customiser.h"
#include "fabatlas/viewer/export_design.h"
#include "fabatlas/viewer/optimise.h"
#include "fabatlas/viewer/pareto_front.h"
#include "fabatlas/viewer/property_limits.h"
#include "fabatlas/write_file_atomically.h"

namespace fabatlas::cli {

namespace {

using nlohmann::json;

struct OptimiseArgs {
  std::string art, min, max, weights, limits;
  std::vector<std::string> hold;
  bool json = false;
};

std::string Joined(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ",") + item;
  return out;
}

void Optimise(const OptimiseArgs& a) {
  const int given = !a.min.empty() + !a.max.empty() + !a.weights.empty();
  if (given != 1) throw InputError("optimise: name exactly one of --min PROPERTY, --max PROPERTY, --weights a=1,b=2");
  const viewer::Customiser c(viewer::LoadArtifact(ArtifactPath(a.art), viewer::CacheChoice::kNone));
  viewer::OptimiseOptions options;
  options.maximise = !a.max.empty();
  options.terms = viewer::ParseObjective(!a.min.empty() ? a.min : !a.max.empty() ? a.max : a.weights);
  options.hold = viewer::ParseHolds(Joined(a.hold), c.space());
  const auto limits = viewer::ParseLimits(a.limits, c.source().materials);
  const auto form = c.LimitedForm(limits);
  const viewer::OptimiseResult r = viewer::Optimise(*form, c.corners(), c.source().materials, options);
  if (!r.found)
    throw InputError(a.art + ": no valid point" + (limits.empty() ? "" : " meets the limits") +
                     (options.hold.empty() ? "" : " at the held values"));
  if (a.json) {
    json values = json::object();
    for (std::size_t k = 0; k < r.values.size(); ++k) values[r.properties[k]] = r.values[k];
    json point = json::object();
    for (int d = 0; d < c.dimension_count(); ++d) point[c.space().dimension(d).name] = r.u[d];
    std::cout << json{{"design", c.source().name},
                      {"u", r.u},
                      {"point", point},
                      {"objective", r.objective},
                      {"maximise", options.maximise},
                      {"values", values},
                      {"sample", r.sample},
                      {"interpolated", r.sample < 0},
                      {"corners", r.corners},
                      {"candidates", r.candidates}}
                     .dump(2)
              << "\n";
    return;
  }
  std::ostringstream what;
  for (std::size_t k = 0; k < options.terms.size(); ++k) {
    if (options.terms.size() > 1) what << (k ? " + " : "") << options.terms[k].weight << "*";
    what << r.properties[k];
  }
  std::cout << "fabatlas optimise: " << c.source().name << ": " << (options.maximise ? "maximum" : "minimum") << " of "
            << what.str() << " = " << r.objective << " at " << viewer::PointText(c, r.u);
  if (r.sample >= 0) {
    std::cout << " (sample " << r.sample << ")";
  } else {
    std::cout << " (interpolated between samples";
    for (std::size_t k = 0; k < r.corners.size(); ++k) std::cout << (k ? ", " : " ") << r.corners[k];
    std::cout << "; not evaluated there)";
  }
  if (options.terms.size() > 1)
    for (std::size_t k = 0; k < r.values.size(); ++k) std::cout << ", " << r.properties[k] << " " << r.values[k];
  std::cout << "; " << r.candidates << " valid candidates" << std::endl;
}

}  // namespace

void AddOptimiseCommands(CLI::App& app, int& exit_code) {
  (void)exit_code;
  auto a = std::make_shared<OptimiseArgs>();
  auto* o = app.add_subcommand("optimise",
                               "the valid design minimising or maximising a property, a weighted sum of "
                               "properties or a material's weight or cost, optionally with parameters held");
  o->add_option("art", a->art, "an artifact (<design>.fabatlas) or the run directory holding it")->required();
  o->add_option("--min", a->min,
                "minimise this property (volume, weight:PLA or weight_PLA, cost:PLA, ...) or weights a=1,b=2");
  o->add_option("--max", a->max, "maximise this property or weighted sum");
  o->add_option("--weights", a->weights, "minimise the weighted sum a=1,b=-2 of properties");
  o->add_option("--hold", a->hold, "hold a parameter at a value: name=value (repeat, or comma-separate)");
  o->add_option("--limits", a->limits, "runtime limits as the page's: volume<=9000,weight:PLA<=10");
  o->add_flag("--json", a->json, "print JSON");
  o->callback([a] { Optimise(*a); });
}

void WritePareto(const std::filesystem::path& artifact, const std::string& axes, const std::string& csv,
                 const std::string& png, const std::string& limits) {
  namespace fs = std::filesystem;
  viewer::ParetoOptions options = viewer::ParseParetoAxes(axes);
  options.keep_dominated = true;
  // A Customiser owns (and removes) the scratch copy of the artifact's bundle.
  const viewer::Customiser c(viewer::LoadArtifact(artifact, viewer::CacheChoice::kNone));
  const auto form = c.LimitedForm(viewer::ParseLimits(limits, c.source().materials));
  const viewer::ParetoFront front = viewer::ParetoFrontOf(*form, c.source().materials, options);
  if (front.points.empty()) throw InputError(artifact.string() + ": no valid sample records both properties");
  const fs::path csv_path = csv.empty() ? fs::path(artifact).replace_extension(".pareto.csv") : fs::path(csv);
  const fs::path png_path = png.empty() ? fs::path(artifact).replace_extension(".pareto.png") : fs::path(png);
  WriteFileAtomically(csv_path, viewer::ParetoCsv(*form, front));
  viewer::WriteParetoPng(front, png_path, {.title = c.source().name});
  std::cout << "Pareto front of " << front.a << " (" << (options.a.maximise ? "max" : "min") << ") and " << front.b
            << " (" << (options.b.maximise ? "max" : "min") << "): " << front.points.size() << " of "
            << front.candidates << " valid samples; wrote " << csv_path.string() << ", " << png_path.string()
            << std::endl;
}

}  // namespace fabatlas::cli
