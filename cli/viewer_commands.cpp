// fabatlas serve ART [--port P] [--cache opt|rfree|none] — the web customiser
// of a published artifact (Fab Forms Sec. 7) over HTTP; docs/viewer.md.
#include <atomic>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <vector>

#include "commands.h"
#include "fabatlas/error.h"
#include "fabatlas/viewer/customiser.h"
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
};

// ART: an artifact file, a run directory holding exactly one artifact, or
// (with --job) a run directory with only form.json.
viewer::CustomiserSource Load(const ServeArgs& a) {
  namespace fs = std::filesystem;
  const fs::path art(a.art);
  const viewer::CacheChoice cache = a.cache == "rfree"  ? viewer::CacheChoice::kRfree
                                    : a.cache == "none" ? viewer::CacheChoice::kNone
                                                        : viewer::CacheChoice::kOpt;
  if (fs::is_regular_file(art)) return viewer::LoadArtifact(art, cache);
  if (!fs::is_directory(art)) throw InputError(a.art + ": no such artifact or run directory");
  std::vector<fs::path> artifacts;
  for (const auto& e : fs::directory_iterator(art))
    if (e.is_regular_file() && e.path().extension() == ".fabatlas") artifacts.push_back(e.path());
  if (artifacts.size() == 1 && a.job.empty()) return viewer::LoadArtifact(artifacts[0], cache);
  if (artifacts.size() > 1 && a.job.empty())
    throw InputError(a.art + ": holds " + std::to_string(artifacts.size()) + " artifacts; name one");
  if (a.job.empty()) throw InputError(a.art + ": no *.fabatlas artifact (a form.json alone needs --job JOB)");
  return viewer::LoadRunDirectory(art, a.job);
}

void Serve(const ServeArgs& a) {
  viewer::Customiser customiser(Load(a));
  viewer::ServeOptions options;
  options.host = a.host;
  options.port = a.port;
  options.web_dir = a.web;
  std::signal(SIGINT, StopServing);
  std::signal(SIGTERM, StopServing);
  viewer::Serve(customiser, options, g_stop, [&](int port) {
    std::cout << "fabatlas serve: customiser for " << customiser.source().name << " at http://" << a.host << ":"
              << port << "/" << std::endl;
  });
}

}  // namespace

void AddViewerCommands(CLI::App& app, int& exit_code) {
  (void)exit_code;
  auto a = std::make_shared<ServeArgs>();
  auto* serve = app.add_subcommand("serve", "serve the web customiser and its JSON/glTF API for a computed form");
  serve->add_option("art", a->art, "an artifact (<design>.fabatlas) or the run directory holding it")->required();
  serve->add_option("--cache", a->cache, "subtrees previews load: opt (H_opt, default), rfree (H_rfree) or none")
      ->check(CLI::IsMember({"opt", "rfree", "none"}));
  serve->add_option("--job", a->job, "serve a run directory's form.json alone, with this job file's design");
  serve->add_option("--port", a->port, "TCP port (0: any free port, printed)")->check(CLI::Range(0, 65535));
  serve->add_option("--host", a->host, "address to listen on (default 127.0.0.1)");
  serve->add_option("--web", a->web, "directory of the built web page (default: PREFIX/share/fabatlas/web when installed, else build/web)");
  serve->callback([a] { Serve(*a); });
}

}  // namespace fabatlas::cli
