// Cluster benchmarks with plain timers (results in docs/benchmarks.md (Cluster)).
//   cluster_bench [--tasks N] [--repeats R] [--blob-mb M] [--idle W] [--job JOB.yaml]
// 1. No-op round trips/s: N no-op tasks through an in-process coordinator to
//    2 fabatlas-worker processes (64 slots each, leases batched per Sync),
//    from submission of the batch to the last stored result.
// 2. Per-task overhead: one no-op task at a time, submit -> result (p50, p99).
// 3. The same no-op throughput while W more workers are connected and idle
//    (each its own TCP connection, syncing with no free slot every 2 s).
// 4. Blob ingest MB/s on loopback (chunked upload, fsync, SHA-256 verify).
// 5. Speed-up of 2 workers over 1 (1 slot each) on a CPU-bound sampling job.
// Medians over R repeats.
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "fabatlas/coordinator/coordinator.h"
#include "fabatlas/coordinator/job_client.h"
#include "fabatlas/protocol/channel.h"
#include "fabatlas/sha256.h"
#include "fabatlas/v1/worker.grpc.pb.h"

namespace fs = std::filesystem;
using namespace fabatlas;
using Clock = std::chrono::steady_clock;

namespace {

double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

pid_t SpawnWorker(int port, int slots, const fs::path& dir) {
  std::string bin = (fs::read_symlink("/proc/self/exe").parent_path() / "fabatlas-worker").string();
  std::string target = "127.0.0.1:" + std::to_string(port), s = std::to_string(slots), cache = dir.string();
  std::string log = (dir.parent_path() / (dir.filename().string() + ".log")).string();
  pid_t pid = fork();
  if (pid == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    FILE* f = std::freopen(log.c_str(), "w", stderr);
    (void)f;
    execl(bin.c_str(), bin.c_str(), "--coordinator", target.c_str(), "--slots", s.c_str(), "--cache-dir",
          cache.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

void StopWorkers(std::vector<pid_t>& pids) {
  for (pid_t p : pids) kill(p, SIGTERM);
  for (pid_t p : pids) waitpid(p, nullptr, 0);
  pids.clear();
}

std::vector<std::string> NoopPayloads(int n, int salt, std::vector<std::string>* keys) {
  std::vector<std::string> payloads;
  keys->clear();
  for (int i = 0; i < n; ++i) {
    v1::TaskPayload p;
    p.set_kind(v1::TASK_KIND_NOOP);
    p.mutable_point_a()->add_key(salt);
    p.mutable_point_a()->add_key(i);
    payloads.push_back(p.SerializeAsString());
    keys->push_back(Sha256Hex("noop/" + std::to_string(salt) + "/" + std::to_string(i)));
  }
  return payloads;
}

double NoopThroughput(coordinator::Coordinator& c, int tasks, int salt) {
  std::vector<std::string> keys;
  auto payloads = NoopPayloads(tasks, salt, &keys);
  auto t0 = Clock::now();
  auto results = c.RunTasks("noop-bench", payloads, keys);
  return static_cast<double>(results.size()) / Seconds(t0, Clock::now());
}

int Arg(int argc, char** argv, const char* name, int fallback) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], name) == 0) return std::atoi(argv[i + 1]);
  return fallback;
}

}  // namespace

int main(int argc, char** argv) {
  int tasks = Arg(argc, argv, "--tasks", 20000);
  int repeats = Arg(argc, argv, "--repeats", 3);
  int blob_mb = Arg(argc, argv, "--blob-mb", 128);
  int idle = Arg(argc, argv, "--idle", 1000);
  fs::path job = fs::path(FABATLAS_BENCH_SOURCE_DIR) / "bench/cluster/data/pawn_small.yaml";
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--job") == 0) job = argv[i + 1];
  fs::path dir = fs::temp_directory_path() / ("fabatlas_cluster_bench_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);

  coordinator::CoordinatorOptions options;
  options.listen = "127.0.0.1:0";
  options.state_dir = dir / "state";
  coordinator::Coordinator c(options);
  c.Start();
  std::string target = "127.0.0.1:" + std::to_string(c.port());
  std::vector<pid_t> workers;
  for (int i = 0; i < 2; ++i) workers.push_back(SpawnWorker(c.port(), 64, dir / ("noop" + std::to_string(i))));
  NoopThroughput(c, 500, 999);  // warm-up: workers connected

  std::vector<double> rates;
  for (int r = 0; r < repeats; ++r) rates.push_back(NoopThroughput(c, tasks, r));
  std::printf("noop round trips: %d tasks x %d repeats, 2 workers x 64 slots: median %.0f tasks/s (runs:", tasks,
              repeats, Median(rates));
  for (double x : rates) std::printf(" %.0f", x);
  std::printf(")\n");

  std::vector<double> latencies;
  for (int i = 0; i < 300; ++i) {
    std::vector<std::string> keys;
    auto payloads = NoopPayloads(1, 100000 + i, &keys);
    auto t0 = Clock::now();
    c.RunTasks("noop-bench", payloads, keys);
    latencies.push_back(1000.0 * Seconds(t0, Clock::now()));
  }
  std::sort(latencies.begin(), latencies.end());
  std::printf("single no-op task round trip (submit -> stored result), 300 tasks: p50 %.2f ms, p99 %.2f ms\n",
              latencies[latencies.size() / 2], latencies[latencies.size() * 99 / 100]);

  // Idle workers: own connections (local subchannel pools), Sync with no free slot.
  if (idle > 0) {
    std::atomic<bool> stop{false};
    std::atomic<long> syncs{0}, failures{0};
    std::vector<std::thread> threads;
    const int kThreads = 8;
    std::vector<double> sync_ms;
    std::mutex sync_mu;
    for (int t = 0; t < kThreads; ++t) {
      threads.emplace_back([&, t] {
        std::vector<std::unique_ptr<v1::WorkerService::Stub>> stubs;
        for (int i = t; i < idle; i += kThreads) {
          grpc::ChannelArguments args;
          args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
          args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, 20000);
          stubs.push_back(v1::WorkerService::NewStub(
              grpc::CreateCustomChannel(target, grpc::InsecureChannelCredentials(), args)));
        }
        while (!stop) {
          auto round = Clock::now();
          for (std::size_t i = 0; i < stubs.size() && !stop; ++i) {
            grpc::ClientContext ctx;
            ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
            v1::SyncRequest req;
            req.set_worker_id("idle-" + std::to_string(t) + "-" + std::to_string(i));
            req.set_free_slots(0);
            v1::SyncResponse resp;
            auto s0 = Clock::now();
            if (stubs[i]->Sync(&ctx, req, &resp).ok()) {
              ++syncs;
              std::lock_guard lock(sync_mu);
              sync_ms.push_back(1000.0 * Seconds(s0, Clock::now()));
            } else {
              ++failures;
            }
          }
          while (!stop && Clock::now() - round < std::chrono::seconds(2))
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
      });
    }
    std::this_thread::sleep_for(std::chrono::seconds(5));  // all connected and syncing
    std::vector<double> busy;
    for (int r = 0; r < repeats; ++r) busy.push_back(NoopThroughput(c, tasks, 1000 + r));
    stop = true;
    for (auto& t : threads) t.join();
    std::sort(sync_ms.begin(), sync_ms.end());
    std::printf("with %d idle workers connected (%ld idle syncs, %ld failed; idle sync p99 %.2f ms): median %.0f "
                "no-op tasks/s\n",
                idle, syncs.load(), failures.load(), sync_ms.empty() ? 0.0 : sync_ms[sync_ms.size() * 99 / 100],
                Median(busy));
  }
  StopWorkers(workers);

  // Blob ingest.
  {
    coordinator::JobClient client(target, {}, std::chrono::seconds(120));
    std::vector<double> mbps;
    std::mt19937_64 rng(1);
    for (int r = 0; r < repeats; ++r) {
      std::string data(static_cast<std::size_t>(blob_mb) << 20, '\0');
      for (std::size_t i = 0; i + 8 <= data.size(); i += 8) {
        std::uint64_t x = rng();
        std::memcpy(&data[i], &x, 8);
      }
      auto t0 = Clock::now();
      client.UploadBlob(data);
      mbps.push_back(blob_mb / Seconds(t0, Clock::now()));
    }
    std::printf("blob ingest (%d MiB, 1 MiB chunks, fsync + SHA-256 verify): median %.0f MiB/s\n", blob_mb,
                Median(mbps));
  }
  c.Shutdown();

  // Speed-up on CPU-bound samples: fresh coordinator state per run.
  if (fs::exists(job)) {
    double wall[3] = {0, 0, 0};
    for (int n : {1, 2}) {
      coordinator::CoordinatorOptions o = options;
      o.state_dir = dir / ("speedup" + std::to_string(n));
      coordinator::Coordinator sc(o);
      sc.Start();
      std::vector<pid_t> pids;
      for (int i = 0; i < n; ++i) pids.push_back(SpawnWorker(sc.port(), 1, dir / ("cpu" + std::to_string(n) + "_" + std::to_string(i))));
      coordinator::JobClient client("127.0.0.1:" + std::to_string(sc.port()), {});
      auto t0 = Clock::now();
      std::string id = client.Submit(job);
      auto s = client.Watch(id, [](const v1::JobStatus&) { return true; });
      wall[n] = Seconds(t0, Clock::now());
      std::printf("%s on %d worker(s) x 1 slot: %.2f s, %lld tasks, state %s\n", job.filename().c_str(), n, wall[n],
                  static_cast<long long>(s.tasks_total()), coordinator::JobStateName(s.state()).c_str());
      StopWorkers(pids);
      sc.Shutdown();
    }
    std::printf("speed-up of 2 workers over 1: %.2fx\n", wall[1] / wall[2]);
  }
  fs::remove_all(dir);
  return 0;
}
