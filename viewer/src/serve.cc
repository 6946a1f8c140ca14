#include "fabatlas/viewer/serve.h"

#include <fstream>
#include <sstream>
#include <thread>

#include <httplib.h>

#include "fabatlas/error.h"
#include "fabatlas/viewer/http_api.h"

namespace fabatlas::viewer {

namespace {

std::string ContentType(const std::filesystem::path& p) {
  const std::string ext = p.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript";
  if (ext == ".css") return "text/css";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".png") return "image/png";
  if (ext == ".json") return "application/json";
  return "application/octet-stream";
}

// An API answer as the HTTP response, never cached; a shared body (a cached
// preview) is sent from its bytes without copying them.
void SendApiResponse(const ApiResponse& r, httplib::Response& res) {
  res.status = r.status;
  for (const auto& [k, v] : r.headers) res.set_header(k, v);
  res.set_header("Cache-Control", "no-store");
  if (r.shared_body) {
    auto body = r.shared_body;
    res.set_content_provider(body->size(), r.content_type.c_str(),
                             [body](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                               return sink.write(body->data() + offset, length);
                             });
  } else {
    res.set_content(r.body, r.content_type);
  }
}

// The routes: the API (GET, and POST for the queries that also take a JSON
// body), the page's own files by exact path, 405 for any other method.
void AddRoutes(httplib::Server& server, const Customiser& customiser, const std::map<std::string, std::string>& files) {
  server.Get(R"(/api/.*)", [&](const httplib::Request& req, httplib::Response& res) {
    std::map<std::string, std::string> query;
    for (const auto& [k, v] : req.params) query[k] = v;
    SendApiResponse(HandleApiRequest(customiser, req.path, query), res);
  });
  // The queries that also take a JSON body (http_api.h, HandleApiPost).
  server.Post(R"(/api/(optimise|pareto))", [&](const httplib::Request& req, httplib::Response& res) {
    SendApiResponse(HandleApiPost(customiser, req.path, req.body), res);
  });
  // Everything else: only the page's own files, looked up by exact path.
  server.Get(R"(.*)", [&](const httplib::Request& req, httplib::Response& res) {
    const auto it = files.find(req.path);
    if (it == files.end()) {
      res.status = 404;
      res.set_content("not found\n", "text/plain; charset=utf-8");
      return;
    }
    res.set_content(it->second, ContentType(it->first == "/" ? "/index.html" : it->first).c_str());
  });
  // Only GET (and POST to the two routes above): anything else is 405 with one line.
  const auto not_allowed = [](const httplib::Request& req, httplib::Response& res) {
    res.status = 405;
    res.set_header("Allow", "GET");
    res.set_content(req.method + " is not allowed here; the customiser's API answers GET only\n",
                    "text/plain; charset=utf-8");
  };
  server.Post(R"(.*)", not_allowed);
  server.Put(R"(.*)", not_allowed);
  server.Delete(R"(.*)", not_allowed);
  server.Patch(R"(.*)", not_allowed);
}

// What every response carries (the page's files, the API's answers and
// errors alike), and the listening socket's options.
void SetServerPolicy(httplib::Server& server) {
  server.set_post_routing_handler([](const httplib::Request&, httplib::Response& res) {
    res.set_header("Content-Security-Policy", kContentSecurityPolicy);
    res.set_header("X-Content-Type-Options", "nosniff");
    res.set_header("Referrer-Policy", "no-referrer");
  });
  server.set_error_handler([](const httplib::Request&, httplib::Response& res) {
    if (res.body.empty()) res.set_content("error " + std::to_string(res.status) + "\n", "text/plain; charset=utf-8");
  });
  // SO_REUSEADDR only: httplib's default also sets SO_REUSEPORT, with which
  // a second server on a taken port would bind and share its connections.
  server.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, reinterpret_cast<const void*>(&yes), sizeof(yes));
  });
}

}  // namespace

std::map<std::string, std::string> ReadWebFiles(const std::filesystem::path& web_dir) {
  if (!std::filesystem::is_regular_file(web_dir / "index.html"))
    throw InputError(web_dir.string() + ": no index.html (build the page: `ninja -C build fabatlas_web`)");
  std::map<std::string, std::string> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(web_dir)) {
    if (!entry.is_regular_file()) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    files["/" + std::filesystem::relative(entry.path(), web_dir).generic_string()] = bytes.str();
  }
  files["/"] = files.at("/index.html");
  return files;
}

void Serve(const Customiser& customiser, const ServeOptions& options, const std::atomic<bool>& stop,
           const std::function<void(int port)>& on_listening) {
  const std::map<std::string, std::string> files = ReadWebFiles(options.web_dir);
  httplib::Server server;
  AddRoutes(server, customiser, files);
  SetServerPolicy(server);
  int port = options.port;
  if (port == 0) {
    port = server.bind_to_any_port(options.host);
  } else if (!server.bind_to_port(options.host, port)) {
    port = -1;
  }
  if (port <= 0) throw ResourceError("cannot listen on " + options.host + ":" + std::to_string(options.port));
  std::thread watcher([&] {
    while (!stop.load() && !server.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (on_listening) on_listening(port);
    while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    server.stop();
  });
  server.listen_after_bind();
  watcher.join();
}

}  // namespace fabatlas::viewer
