// fabatlas/viewer/serve.h — `fabatlas serve`: the customiser over HTTP
// (cpp-httplib). Serves only the API (http_api.h) and the files of the built
// web page, read into memory at start-up: any other path is 404, so nothing
// outside them is reachable whatever the request path contains. Every
// response carries kContentSecurityPolicy and `X-Content-Type-Options:
// nosniff`; API errors are text/plain, never HTML.
#pragma once

#include <atomic>
#include <filesystem>
#include <functional>
#include <map>
#include <string>

#include "fabatlas/viewer/customiser.h"

namespace fabatlas::viewer {

// The Content-Security-Policy of every response: the page's own script and
// style files only (no inline script or style, no eval), data and blob
// images (the starting-point thumbnails), fetches to the same origin only,
// no plugins, frames, forms or <base>. A string of an artifact that somehow
// reached the page as markup still could not run (W3C Content Security
// Policy Level 3).
inline constexpr const char* kContentSecurityPolicy =
    "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; "
    "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'; object-src 'none'";

struct ServeOptions {
  std::string host = "127.0.0.1";
  int port = 8080;                // 0: any free port (reported through on_listening)
  std::filesystem::path web_dir;  // the built page (build/web); must hold index.html
};

// The files of the built page by URL path ("/index.html", "/assets/x.js"),
// with "/" mapped to index.html. Throws InputError if web_dir has no
// index.html (build it: `ninja -C build fabatlas_web`).
std::map<std::string, std::string> ReadWebFiles(const std::filesystem::path& web_dir);

// Blocks serving until `stop` becomes true (checked a few times a second) or
// the process ends. on_listening(port) runs once the socket is bound.
// Throws ResourceError if the port cannot be bound.
void Serve(const Customiser& customiser, const ServeOptions& options, const std::atomic<bool>& stop,
           const std::function<void(int port)>& on_listening = {});

}  // namespace fabatlas::viewer
