// fabatlas serve ART [--port P] [--cache opt|rfree|none] — the web customiser
// of a published artifact (Fab Forms Sec. 7) over HTTP; docs/viewer.md.
// fabatlas export ART --at name=value,... --format stl|3mf|glb|obj --out FILE
// — the design at exactly that valid point, at fabrication resolution.
#include <atomic>
#include <cctype>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <thread>
#include <vector>

#include <unistd.h>

#include "commands.h"
#include "fabatlas/design/design.h"
#include "fabatlas/error.h"
#include "fabatlas/viewer/customiser.h"
#include "fabatlas/viewer/export_design.h"
#include "fabatlas/viewer/serve.h"

namespace fabatlas::cli {

namespace {

std::atomic<bool> g_stop{false};

extern "C" void StopServing(int) { g_stop.store(true); }

// The built page: beside an installed fabatlas (PREFIX/share/fabatlas/web,
// ops/CMakeLists.txt), else the build tree's.
std::string DefaultWebDir() {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path installed = fs::read_symlink("/proc/self/exe", ec).parent_path().parent_path() / "share/fabatlas/web";
  if (!ec && fs::is_regular_file(installed / "index.html", ec)) return installed.string();
  return FABATLAS_WEB_DIR;
}

struct ServeArgs {
  std::string art, job, host = "127.0.0.1", web = DefaultWebDir(), cache = "opt";
  int port = 8080;
  int preview_cache_mb = 192;
  double exact_budget_ms = 150;
};

// ART: an artifact file, a run directory holding exactly one artifact, or
// (with --job) a run directory with only form.json.
viewer::CustomiserSource Load(const std::string& arg, const std::string& job, const std::string& cache_name) {
  namespace fs = std::filesystem;
  const viewer::CacheChoice cache = cache_name == "rfree"  ? viewer::CacheChoice::kRfree
                                    : cache_name == "none" ? viewer::CacheChoice::kNone
                                                           : viewer::CacheChoice::kOpt;
  if (!job.empty()) {
    if (!fs::is_directory(arg)) throw InputError(arg + ": --job needs the run directory holding form.json");
    return viewer::LoadRunDirectory(arg, job);
  }
  return viewer::LoadArtifact(ArtifactPath(arg), cache);
}

void Serve(const ServeArgs& a) {
  viewer::PreviewCacheOptions previews;
  previews.max_bytes = static_cast<std::size_t>(a.preview_cache_mb) << 20;
  viewer::ExactPreviewOptions exact;
  exact.budget_seconds = a.exact_budget_ms / 1000;
  viewer::Customiser customiser(Load(a.art, a.job, a.cache), previews, exact);
  viewer::ServeOptions options;
  options.host = a.host;
  options.port = a.port;
  options.web_dir = a.web;
  std::signal(SIGINT, StopServing);
  std::signal(SIGTERM, StopServing);
  // One background thread fills the preview cache while requests are served.
  std::thread warm;
  viewer::Serve(customiser, options, g_stop, [&](int port) {
    std::cout << "fabatlas serve: customiser for " << customiser.source().name << " at http://" << a.host << ":" << port
              << "/" << std::endl;
    warm = std::thread([&] {
      try {
        const auto start = std::chrono::steady_clock::now();
        const int n = customiser.WarmPreviews(g_stop);
        const auto stats = customiser.preview_cache_stats();
        std::cout << "fabatlas serve: preview cache warm: " << n << " previews evaluated, " << stats.entries
                  << " held, " << (stats.bytes >> 20) << " MiB, "
                  << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() << " s"
                  << std::endl;
      } catch (const std::exception& e) {
        std::cerr << "fabatlas serve: warming the preview cache stopped: " << e.what() << std::endl;
      }
    });
  });
  g_stop = true;
  if (warm.joinable()) warm.join();
}

struct ExportArgs {
  std::string art, job, at, format, out, part;
  double voxel_size = 0;
};

// The point of --at: named parameters as given, the others at their default
// (design::ParsePoint), in the form's order.
std::vector<double> PointOf(const viewer::Customiser& c, const std::string& at) {
  const design::Point point = design::ParsePoint(*c.source().design, at, "--at");
  std::vector<double> u;
  for (int d = 0; d < c.dimension_count(); ++d) u.push_back(point.at(c.space().dimension(d).name));
  return u;
}

void Export(const ExportArgs& a) {
  namespace fs = std::filesystem;
  std::string format = a.format;
  if (format.empty()) {
    format = fs::path(a.out).extension().string();
    if (!format.empty()) format = format.substr(1);
    for (char& ch : format) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  }
  viewer::Customiser customiser(Load(a.art, a.job, "none"));
  if (!customiser.source().design) throw InputError(a.art + ": holds no design to export");
  viewer::ExportOptions options;
  options.format = format;
  options.voxel_size = a.voxel_size;
  options.part = a.part;
  const viewer::ExportResult r = viewer::ExportDesign(customiser, PointOf(customiser, a.at), options);
  const fs::path out(a.out);
  const fs::path temp = out.string() + ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream file(temp, std::ios::binary);
    file.write(r.bytes.data(), static_cast<std::streamsize>(r.bytes.size()));
    file.close();
    if (!file) {
      std::error_code ec;
      fs::remove(temp, ec);
      throw InputError(a.out + ": cannot write the file");
    }
  }
  std::error_code ec;
  fs::rename(temp, out, ec);
  if (ec) {
    fs::remove(temp, ec);
    throw InputError(a.out + ": cannot write the file");
  }
  std::cout << "fabatlas export: " << a.out << ": " << customiser.source().name << " at "
            << viewer::PointText(customiser, r.u) << ", " << r.triangles << " triangles, volume " << r.volume_mm3
            << " mm^3, voxel " << r.voxel_size << " mm, " << r.seconds << " s, checks passed there: ";
  for (std::size_t k = 0; k < r.checks.size(); ++k) std::cout << (k ? ", " : "") << r.checks[k];
  std::cout << "; parts: ";
  for (std::size_t k = 0; k < r.parts.size(); ++k) std::cout << (k ? ", " : "") << r.parts[k];
  std::cout << std::endl;
}

}  // namespace

std::filesystem::path ArtifactPath(const std::string& arg) {
  namespace fs = std::filesystem;
  const fs::path art(arg);
  if (fs::is_regular_file(art)) return art;
  if (!fs::is_directory(art)) throw InputError(arg + ": no such file or run directory");
  std::vector<fs::path> artifacts;
  for (const auto& e : fs::directory_iterator(art))
    if (e.is_regular_file() && e.path().extension() == ".fabatlas") artifacts.push_back(e.path());
  if (artifacts.size() > 1)
    throw InputError(arg + ": holds " + std::to_string(artifacts.size()) + " artifacts; name one");
  if (artifacts.empty()) throw InputError(arg + ": no *.fabatlas artifact (a form.json alone needs --job JOB)");
  return artifacts[0];
}

void AddViewerCommands(CLI::App& app, int& exit_code) {
  (void)exit_code;
  auto e = std::make_shared<ExportArgs>();
  auto* ex = app.add_subcommand("export", "write the design at one valid point as STL, 3MF, glTF or OBJ");
  ex->add_option("art", e->art, "an artifact (<design>.fabatlas) or the run directory holding it")->required();
  ex->add_option("--at", e->at, "the point: name=value,... (others at their default)")->required();
  ex->add_option("--format", e->format, "stl, 3mf, glb or obj (default: from --out's extension)")
      ->check(CLI::IsMember({"stl", "3mf", "glb", "obj"}));
  ex->add_option("--out", e->out, "the file to write")->required();
  ex->add_option("--voxel-size", e->voxel_size, "mm (default: half the design's voxel size)")
      ->check(CLI::PositiveNumber);
  ex->add_option("--part", e->part, "stl, obj: only this part (a body or colour region, as the output lists them)");
  ex->add_option("--job", e->job, "export from a run directory's form.json alone, with this job file's design");
  ex->callback([e] { Export(*e); });
  auto a = std::make_shared<ServeArgs>();
  auto* serve = app.add_subcommand("serve", "serve the web customiser and its JSON/glTF API for a computed form");
  serve->add_option("art", a->art, "an artifact (<design>.fabatlas) or the run directory holding it")->required();
  serve->add_option("--cache", a->cache, "subtrees previews load: opt (H_opt, default), rfree (H_rfree) or none")
      ->check(CLI::IsMember({"opt", "rfree", "none"}));
  serve->add_option("--job", a->job, "serve a run directory's form.json alone, with this job file's design");
  serve->add_option("--port", a->port, "TCP port (0: any free port, printed)")->check(CLI::Range(0, 65535));
  serve->add_option("--host", a->host, "address to listen on (default 127.0.0.1)");
  serve->add_option(
      "--web", a->web,
      "directory of the built web page (default: PREFIX/share/fabatlas/web when installed, else build/web)");
  serve
      ->add_option("--preview-cache-mb", a->preview_cache_mb,
                   "memory for encoded previews, filled in the background at start (default 192; 0: none)")
      ->check(CLI::Range(0, 1 << 20));
  serve
      ->add_option("--exact-budget-ms", a->exact_budget_ms,
                   "previews at the sliders' exact point when one is expected to take at most this long "
                   "(default 150; 0: always the snapped sample)")
      ->check(CLI::Range(0.0, 600000.0));
  serve->callback([a] { Serve(*a); });
}

}  // namespace fabatlas::cli
