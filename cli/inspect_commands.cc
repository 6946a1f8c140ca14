// fabatlas inspect ART [--json] [--png PATH] [--points N] [--pareto A,B] [--params] — what a published
// artifact (docs/artifact.md) holds, as the rows of Fab Forms' evaluation:
//   Table 3: samples, CPU time, valid volume %, failure shares;
//   Fig. 14: H_TOP, H_opt and H_rfree sizes, and mean / worst preview time
//            with no cache, with H_opt and with H_rfree, measured by
//            re-evaluating the design from the artifact's bundle at N random
//            points of the valid region (default 200, as in the paper), each
//            snapped as the customiser snaps (Sec. 7.3, ΔG-weighted), beside
//            what the cache plan's cost model predicts for the same previews
//            (and, in --json, both per subtree operation);
//   Fig. 13: mean and worst predicted preview time against cache size for
//            the three strategies, written as a PNG.
// The CPU time is a measurement of the run, kept out of the (deterministic)
// artifact: it is read from statistics.json beside the artifact when present.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "commands.h"
#include "fabatlas/pipeline/artifact_of.h"
#include "fabatlas/design/design.h"
#include "fabatlas/error.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/precompute/cache_curves_plot.h"
#include "fabatlas/precompute/preview_times.h"
#include "fabatlas/precompute/preview_times_plot.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/viewer/customiser.h"
#include "fabatlas/viewer/http_api.h"
#include "fabatlas/viewer/snap.h"

namespace fabatlas::cli {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct InspectArgs {
  std::string artifact, png, fig14_png, pareto, pareto_csv, pareto_png, limits;
  bool json = false, params = false;
  int points = 200;
  std::uint64_t seed = 1;
};

// evaluator_cpu_seconds from statistics.json beside the artifact, if any.
std::optional<double> RunCpuSeconds(const fs::path& artifact) {
  const fs::path stats = artifact.parent_path() / "statistics.json";
  std::ifstream in(stats);
  if (!in) return std::nullopt;
  try {
    json j = json::parse(in);
    return j.at("evaluator_cpu_seconds").get<double>();
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::string MiB(std::int64_t bytes) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(2) << static_cast<double>(bytes) / (1 << 20) << " MiB";
  return out.str();
}

std::string Seconds(double s) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(s < 1 ? 4 : 2) << s << " s";
  return out.str();
}

json TimesJson(const std::optional<precompute::PreviewTimes>& t) {
  if (!t) return nullptr;
  json operations = json::object();
  for (const auto& [op, c] : t->operations)
    operations[op] = {
        {"subtrees", c.subtrees}, {"measured_seconds", c.measured_seconds}, {"model_seconds", c.model_seconds}};
  return json{{"mean_seconds", t->mean_seconds},
              {"worst_seconds", t->worst_seconds},
              {"predicted_mean_seconds", t->predicted_mean_seconds},
              {"predicted_worst_seconds", t->predicted_worst_seconds},
              {"points", t->seconds.size()},
              {"failures", t->failures},
              {"operations", operations}};
}

std::string TimesText(const std::optional<precompute::PreviewTimes>& t) {
  if (!t) return "n/a";
  return "mean " + Seconds(t->mean_seconds) + " worst " + Seconds(t->worst_seconds) + " (plan predicts mean " +
         Seconds(t->predicted_mean_seconds) + " worst " + Seconds(t->predicted_worst_seconds) + ")";
}

// Table 3's row: design, |U|, samples, CPU time, valid volume and failure shares.
std::string Table3Text(const artifact::Artifact& art, const std::optional<double>& cpu) {
  const artifact::Manifest& m = art.manifest;
  const auto& s = m.statistics;
  std::ostringstream table3;
  table3 << m.design_name << "  |U|=" << art.form.dimensions.size() << "  samples " << s.samples << "  CPU "
         << (cpu ? Seconds(*cpu) : std::string("n/a")) << "  valid " << std::fixed << std::setprecision(1)
         << s.valid_volume_percent << "%  failures: ";
  if (s.failure_shares.empty()) table3 << "none";
  bool first = true;
  for (const auto& [type, share] : s.failure_shares) {
    table3 << (first ? "" : ", ") << std::setprecision(0) << 100 * share << "% " << type;
    first = false;
  }
  return table3.str();
}

// Fig. 14's measurements: the points previewed and the preview times with no
// cache, with H_opt and with H_rfree (each absent when not measured).
struct PreviewMeasurements {
  std::vector<std::vector<double>> points;
  std::optional<precompute::PreviewTimes> none, opt, rfree;
};

// Fig. 14: preview times at random valid points.
// Random points of the valid region, each snapped exactly as the
// customiser snaps a preview (viewer::SnapToValidSample, ΔG-weighted,
// Fab Forms Sec. 7.3).
PreviewMeasurements MeasurePreviews(const fs::path& path, const artifact::Artifact& art, const design::Design& design,
                                    const InspectArgs& a) {
  const artifact::Manifest& m = art.manifest;
  PreviewMeasurements p;
  const sampling::DesignSpace space = art.form.space();
  for (const auto& u : precompute::RandomValidPoints(art.form, a.points, a.seed))
    if (auto snapped = viewer::SnapToValidSample(art.form, space, u))
      p.points.push_back(art.form.samples[static_cast<std::size_t>(snapped->sample)].u);
  if (p.points.empty()) return p;
  p.none = precompute::MeasurePreviewTimes(design, p.points, nullptr);
  // One cache in memory at a time (H_opt, then H_rfree), and only when
  // the artifact stores every entry of it (H_rfree's entries beyond H_opt
  // are stored only with `cache: {store_rfree: true}`, docs/artifact.md).
  auto measure = [&](bool artifact::CacheEntry::*member,
                     std::int64_t entries) -> std::optional<precompute::PreviewTimes> {
    std::int64_t stored = 0;
    for (const auto& e : art.cache) stored += e.*member;
    if (stored != entries) return std::nullopt;
    precompute::FrozenSubtreeCache cache;
    artifact::ReadCacheGeometry(
        path, [&](const artifact::CacheEntry& e) { return e.*member; },
        [&](artifact::CacheEntry& e) { cache.Add(e.key, geometry::Solid::Deserialize(e.grid)); });
    return precompute::MeasurePreviewTimes(design, p.points, &cache);
  };
  if (!m.cache.strategy.empty() && !art.cache.empty()) {
    p.opt = measure(&artifact::CacheEntry::in_opt, m.cache.opt_entries);
    p.rfree = measure(&artifact::CacheEntry::in_rfree, m.cache.rfree_entries);
  }
  return p;
}

// Fig. 14 as box plots of the measured times; the PNG's path, or "" when
// nothing was measured.
std::string WriteFig14(const fs::path& path, const artifact::Manifest& m, const PreviewMeasurements& p,
                       const InspectArgs& a) {
  if (!p.none) return "";
  const fs::path out = a.fig14_png.empty() ? fs::path(path).replace_extension(".fig14.png") : fs::path(a.fig14_png);
  std::vector<precompute::PreviewTimesSeries> series = {{"no cache", p.none->seconds}};
  if (p.opt) series.push_back({"H_opt", p.opt->seconds});
  if (p.rfree) series.push_back({"H_rfree", p.rfree->seconds});
  precompute::WritePreviewTimesPng(
      series, out, {.title = m.design_name + ": preview time at " + std::to_string(p.points.size()) + " valid points"});
  return out.string();
}

// Fig. 13; the PNG's path, or "" when the artifact has no cache curves.
std::string WriteFig13(const fs::path& path, const artifact::Artifact& art, const InspectArgs& a) {
  if (art.cache_curves.empty()) return "";
  fs::path out = a.png.empty() ? fs::path(path).replace_extension(".fig13.png") : fs::path(a.png);
  precompute::WriteCacheCurvesPng(art.cache_curves, out, {.title = art.manifest.design_name});
  return out.string();
}

// Everything inspect reports of one artifact.
struct InspectReport {
  fs::path path;
  const artifact::Manifest& m;
  std::optional<double> cpu;
  std::string table3;
  PreviewMeasurements previews;
  std::string fig13_png, fig14_png;
};

void PrintJson(const InspectReport& r, const InspectArgs& a) {
  const artifact::Manifest& m = r.m;
  const auto& s = m.statistics;
  const bool has_cache = !m.cache.strategy.empty();
  json j;
  j["artifact"] = r.path.string();
  j["schema_version"] = m.schema_version;
  j["design"] = m.design_name;
  j["design_hash"] = m.design_hash;
  j["code_version"] = m.code_version;
  j["table3"] = {{"samples", s.samples},
                 {"valid_samples", s.valid_samples},
                 {"cpu_seconds", r.cpu ? json(*r.cpu) : json(nullptr)},
                 {"valid_volume_percent", s.valid_volume_percent},
                 {"failure_shares", s.failure_shares}};
  auto size = [&](std::int64_t entries, std::int64_t bytes) {
    return has_cache ? json{{"entries", entries}, {"bytes", bytes}} : json(nullptr);
  };
  j["fig14"] = {{"cache_strategy", m.cache.strategy},
                {"h_top", size(m.cache.top_entries, m.cache.top_bytes)},
                {"h_opt", size(m.cache.opt_entries, m.cache.opt_bytes)},
                {"h_rfree", size(m.cache.rfree_entries, m.cache.rfree_bytes)},
                {"points", r.previews.points.size()},
                {"seed", a.seed},
                {"t_nocache", TimesJson(r.previews.none)},
                {"t_opt", TimesJson(r.previews.opt)},
                {"t_rfree", TimesJson(r.previews.rfree)}};
  j["fig13_png"] = r.fig13_png.empty() ? json(nullptr) : json(r.fig13_png);
  j["fig14_png"] = r.fig14_png.empty() ? json(nullptr) : json(r.fig14_png);
  std::cout << j.dump(2) << "\n";
}

void PrintText(const InspectReport& r) {
  const artifact::Manifest& m = r.m;
  std::cout << "artifact " << r.path.string() << "  schema v" << m.schema_version << "  design " << m.design_name
            << "  hash " << m.design_hash.substr(0, 16) << "  code " << m.code_version << "\n";
  std::cout << "Table 3: " << r.table3 << "\n";
  std::cout << "Fig. 14: ";
  if (!m.cache.strategy.empty())
    std::cout << "H_TOP " << MiB(m.cache.top_bytes) << "  H_opt " << MiB(m.cache.opt_bytes) << "  H_rfree "
              << MiB(m.cache.rfree_bytes) << " (" << m.cache.strategy << ")";
  else
    std::cout << "no geometry cache in the artifact";
  std::cout << "\n         preview over " << r.previews.points.size() << " random valid points: no cache "
            << TimesText(r.previews.none) << "  H_opt " << TimesText(r.previews.opt) << "  H_rfree "
            << TimesText(r.previews.rfree) << (r.fig14_png.empty() ? "" : "; box plots: " + r.fig14_png) << "\n";
  std::cout << "Fig. 13: " << (r.fig13_png.empty() ? "no cache curves in the artifact" : "wrote " + r.fig13_png)
            << "\n";
}

// The parameter schema only: /api/params's answer, one implementation.
void PrintParams(const fs::path& path) {
  const viewer::Customiser c(viewer::LoadArtifact(path, viewer::CacheChoice::kNone));
  const viewer::ApiResponse r = viewer::HandleApiRequest(c, "/api/params", {});
  if (r.status != 200) throw InputError(path.string() + ": " + r.body);
  std::cout << json::parse(r.body).dump(2) << "\n";
}

void Inspect(const InspectArgs& a, int& exit_code) {
  const fs::path path = ArtifactPath(a.artifact);  // the file, or the run directory holding it (as serve)
  if (a.points < 0) throw InputError("inspect: --points must be >= 0");
  if (a.params) {
    PrintParams(path);
    exit_code = 0;
    return;
  }
  if (!a.pareto.empty()) {  // the trade-off only (optimise_commands.cc)
    WritePareto(path, a.pareto, a.pareto_csv, a.pareto_png, a.limits);
    exit_code = 0;
    return;
  }
  // Metadata only: the cache's geometry is read set by set below, so the
  // memory holds the form and one preview cache, not the whole file.
  const artifact::Artifact art = artifact::ReadArtifact(path, {.load_geometry = false});

  // The design, from the artifact's own bundle (its files stay on disk until
  // the report is printed).
  const fs::path scratch = fs::temp_directory_path() / ("fabatlas-inspect-" + std::to_string(::getpid()));
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{scratch};
  const auto files = protocol::Materialize(pipeline::ProtoBundle(art.bundle), scratch);
  const design::Design design = design::LoadDesign(files.design_file);
  if (design.exposed.size() != art.form.dimensions.size())
    throw InputError(path.string() + ": the bundled design has " + std::to_string(design.exposed.size()) +
                     " exposed parameters, the form " + std::to_string(art.form.dimensions.size()));

  InspectReport report{path, art.manifest, RunCpuSeconds(path), {}, {}, {}, {}};
  report.table3 = Table3Text(art, report.cpu);
  report.previews = MeasurePreviews(path, art, design, a);
  report.fig14_png = WriteFig14(path, art.manifest, report.previews, a);
  report.fig13_png = WriteFig13(path, art, a);
  if (a.json)
    PrintJson(report, a);
  else
    PrintText(report);
  exit_code = 0;
}

}  // namespace

void AddInspectCommands(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<InspectArgs>();
  auto* inspect = app.add_subcommand(
      "inspect",
      "show an artifact's statistics (samples, CPU time, valid volume, failure shares, cache sizes: Fab Forms Table 3) "
      "and preview times (Fig. 14), and plot preview time against cache size (Fig. 13)");
  inspect->add_option("artifact", a->artifact, "an artifact (<design>.fabatlas) or the run directory holding it")
      ->required();
  inspect->add_flag("--json", a->json, "print JSON");
  inspect->add_flag(
      "--params", a->params,
      "instead: the parameter schema as JSON (exposed and fixed parameters, groups, ranges; /api/params)");
  inspect->add_option("--png", a->png, "where to write the Fig. 13 curves (default: ART with .fig13.png)");
  inspect->add_option("--fig14-png", a->fig14_png,
                      "where to write the Fig. 14 preview-time box plots (default: ART with .fig14.png)");
  inspect->add_option("--points", a->points, "random valid points for the preview times (default 200)");
  inspect->add_option("--seed", a->seed, "seed of the random points (default 1)");
  inspect->add_option("--pareto", a->pareto,
                      "instead: the Pareto front of two properties over the valid samples, A,B (each optionally "
                      "min: or max:, default min), written as CSV and PNG");
  inspect->add_option("--pareto-csv", a->pareto_csv, "where --pareto writes the CSV (default: ART with .pareto.csv)");
  inspect->add_option("--pareto-png", a->pareto_png, "where --pareto writes the plot (default: ART with .pareto.png)");
  inspect->add_option("--limits", a->limits, "with --pareto: runtime limits as the page's (volume<=9000,...)");
  inspect->callback([a, &exit_code] { Inspect(*a, exit_code); });
}

}  // namespace fabatlas::cli
