// fabatlas serve ART [--job JOB] [--port P] — the web customiser of a computed
// form (seed 001 Sec. 7) over HTTP; docs/viewer.md.
#include <atomic>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands.h"
#include "fabatlas/error.h"
#include "fabatlas/viewer/customiser.h"
#include "fabatlas/viewer/serve.h"

namespace fabatlas::cli {

namespace {

std::atomic<bool> g_stop{false};

extern "C" void StopServing(int) { g_stop.store(true); }

struct ServeArgs {
  std::string art, job, host = "127.0.0.1", web = FABATLAS_WEB_DIR;
  int port = 8080;
};

void Serve(const ServeArgs& a) {
  const std::filesystem::path art(a.art);
  if (!std::filesystem::is_directory(art))
    throw InputError(a.art + ": not a run directory (expected the --out DIR of `fabatlas run` holding form.json)");
  if (a.job.empty()) throw InputError(a.art + ": a run directory needs --job JOB (the job file that produced it)");
  viewer::Customiser customiser(viewer::LoadRunDirectory(art, a.job));
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
  serve->add_option("art", a->art, "the form: a run's --out directory (form.json)")->required();
  serve->add_option("--job", a->job, "the job file that produced it (design, materials)");
  serve->add_option("--port", a->port, "TCP port (0: any free port, printed)")->check(CLI::Range(0, 65535));
  serve->add_option("--host", a->host, "address to listen on (default 127.0.0.1)");
  serve->add_option("--web", a->web, "the built page (default: build/web)");
  serve->callback([a] { Serve(*a); });
}

}  // namespace fabatlas::cli
