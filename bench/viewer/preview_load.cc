// bench_viewer_preview_load ART [CLIENTS=8] [REQUESTS=800] [SEED=2] — many
// users at once: `fabatlas serve`'s HTTP server (viewer::Serve, in this
// process on a free port) under CLIENTS concurrent clients, each asking
// /api/preview.glb for uniformly random points of the whole design space,
// one new TCP connection per request (as a browser tab or urllib does).
// REQUESTS previews per pass, three passes:
//   no cache: the encoded-preview cache off (every preview evaluates: the peer);
//   cold:     cache on, empty at the start;
//   warm:     the same cache again, with fresh random points;
//   prewarmed: after Customiser::WarmPreviews (what serve does in the
//             background at start), fresh random points again.
// Prints previews/s, p50 / p99 / max latency in ms and the cache's hits,
// misses and bytes. The server uses cpp-httplib's thread pool as serve does.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <httplib.h>

#include "fabatlas/viewer/customiser.h"
#include "fabatlas/viewer/serve.h"

using namespace fabatlas;
using Clock = std::chrono::steady_clock;

namespace {

struct Pass {
  double rate = 0, p50 = 0, p99 = 0, max = 0;
  int errors = 0;
};

Pass Run(const viewer::Customiser& c, int port, int clients, int requests, unsigned seed) {
  std::vector<double> latencies;
  std::mutex mu;
  std::atomic<int> errors{0};
  const auto start = Clock::now();
  std::vector<std::thread> threads;
  for (int k = 0; k < clients; ++k)
    threads.emplace_back([&, k] {
      std::mt19937_64 rng(seed * 1000 + k);
      std::vector<double> mine;
      for (int i = 0; i < requests / clients; ++i) {
        std::string u;
        for (int d = 0; d < c.dimension_count(); ++d) {
          const auto& dim = c.space().dimension(d);
          double v = std::uniform_real_distribution<double>(dim.lo, dim.hi)(rng);
          if (dim.kind != sampling::DimensionKind::kReal) v = std::round(v);
          u += (d ? "," : "") + std::to_string(v);
        }
        const auto t = Clock::now();
        httplib::Client client("127.0.0.1", port);
        auto r = client.Get("/api/preview.glb?u=" + u);
        if (!r || r->status != 200 || r->body.substr(0, 4) != "glTF") ++errors;
        mine.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t).count());
      }
      std::lock_guard<std::mutex> lock(mu);
      latencies.insert(latencies.end(), mine.begin(), mine.end());
    });
  for (auto& t : threads) t.join();
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::sort(latencies.begin(), latencies.end());
  Pass p;
  p.rate = latencies.size() / seconds;
  p.p50 = latencies[latencies.size() / 2];
  p.p99 = latencies[std::min(latencies.size() - 1, latencies.size() * 99 / 100)];
  p.max = latencies.back();
  p.errors = errors;
  return p;
}

void Print(const char* what, const Pass& p, const viewer::Customiser& c) {
  const auto s = c.preview_cache_stats();
  std::printf(
      "%-9s %7.0f previews/s  p50 %7.1f ms  p99 %7.1f ms  max %7.1f ms  errors %d  cache hits %lld misses %lld entries "
      "%zu bytes %zu\n",
      what, p.rate, p.p50, p.p99, p.max, p.errors, static_cast<long long>(s.hits), static_cast<long long>(s.misses),
      s.entries, s.bytes);
  std::fflush(stdout);
}

// Serves c on a free port while body(port) runs.
template <typename Body>
void Serving(const viewer::Customiser& c, Body body) {
  std::atomic<bool> stop{false};
  std::atomic<int> port{0};
  viewer::ServeOptions options;
  options.port = 0;
  options.web_dir = FABATLAS_WEB_DIR;
  std::thread server([&] { viewer::Serve(c, options, stop, [&](int p) { port = p; }); });
  while (port == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  body(port.load());
  stop = true;
  server.join();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_viewer_preview_load ART [CLIENTS=8] [REQUESTS=800] [SEED=2]\n");
    return 2;
  }
  const int clients = argc > 2 ? std::atoi(argv[2]) : 8;
  const int requests = argc > 3 ? std::atoi(argv[3]) : 800;
  const unsigned seed = argc > 4 ? static_cast<unsigned>(std::atoi(argv[4])) : 2;
  std::printf("%s: %d clients, %d previews per pass, hardware threads %u\n", argv[1], clients, requests,
              std::thread::hardware_concurrency());
  {
    viewer::PreviewCacheOptions off;
    off.max_bytes = 0;
    viewer::Customiser c(viewer::LoadArtifact(argv[1]), off);
    Serving(c, [&](int port) { Print("no cache", Run(c, port, clients, requests, seed), c); });
  }
  viewer::Customiser c(viewer::LoadArtifact(argv[1]));
  Serving(c, [&](int port) {
    Print("cold", Run(c, port, clients, requests, seed), c);
    Print("warm", Run(c, port, clients, requests, seed + 1), c);
    std::atomic<bool> never{false};
    const int warmed = c.WarmPreviews(never);
    std::printf("warmed: %d more previews evaluated\n", warmed);
    Print("prewarmed", Run(c, port, clients, requests, seed + 2), c);
  });
  return 0;
}
