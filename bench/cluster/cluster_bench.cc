// Cluster benchmarks with plain timers (results in docs/benchmarks.md (Cluster)).
//   cluster_bench [--tasks N] [--repeats R] [--blob-mb M] [--idle W] [--job JOB.yaml]
//                 [--speedup-repeats S] [--only noop|overhead|idle|blob|speedup] [--fsync-commits]
//                 [--overhead-slots K]
// 1. No-op round trips/s: N no-op tasks through an in-process coordinator to
//    2 fabatlas-worker processes (64 slots each, leases batched per Sync),
//    from submission of the batch to the last stored result; and the
//    coordinator's CPU time per task (CPU time of this process, which is the
//    coordinator, over the run, divided by the tasks).
// 2. Coordinator overhead per task: one no-op task at a time through one
//    idle worker that is long-polling (--overhead-slots, default 1: a
//    1-slot worker runs the task on its sync thread, more slots on slot
//    threads, docs/protocol.md); the wall time from the driver
//    adding the task (RunTasks) to its result being handed back, i.e. the
//    whole round trip of a task that does no work: store insert, wake-up and
//    lease grant, the Sync answer, the worker's next Sync with the result,
//    the store update and the hand-over (p50, p99 of 1,000 tasks).
// 3. The same no-op throughput while W more workers are connected and idle
//    (each its own TCP connection, syncing with no free slot every 2 s).
// 4. Blob ingest MB/s on loopback (chunked upload, fsync, SHA-256 verify).
// 5. Speed-up of 2 workers over 1 (1 slot each, so each worker evaluates on
//    one thread: fabatlas-worker --threads defaults to --slots) on a
//    CPU-bound sampling job (--job, default pawn_small.yaml), with fresh
//    coordinator state per run, runs alternating 1, 2, 1, 2, ...; the
//    workers are connected before the job is submitted. Per pair and as
//    medians: the wall-time ratio, and the CPU-time ratio = CPU of the
//    1-worker run / CPU of the busier worker of the 2-worker run, both
//    counted from submission to the job's end (/proc/PID/stat; process
//    start and exit excluded). Also the coordinator's CPU time per task,
//    the workers' whole-process CPU (rusage after exit), solids downloaded
//    and subtrees computed. --no-lease-affinity turns lease affinity off
//    (docs/protocol.md) for comparison.
// Medians over R (S for the speed-up) repeats.
#include <CLI/CLI.hpp>

#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fabatlas/coordinator/coordinator.h"
#include "fabatlas/coordinator/job_client.h"
#include "fabatlas/coordinator/run_tasks.h"
#include "fabatlas/log/log.h"
#include "fabatlas/protocol/channel.h"
#include "fabatlas/sha256.h"
#include "fabatlas/storage/job_store.h"
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
    execl(bin.c_str(), bin.c_str(), "--coordinator", target.c_str(), "--slots", s.c_str(), "--cache-dir", cache.c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

double CpuSeconds(const rusage& u) {
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// CPU seconds of this process so far (the in-process coordinator).
double ProcessCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return CpuSeconds(u);
}

// Stops the workers (SIGTERM: finish, return leases, exit); returns their
// total CPU seconds.
double StopWorkers(std::vector<pid_t>& pids, double* max_cpu = nullptr) {
  for (pid_t p : pids) kill(p, SIGTERM);
  double cpu = 0;
  if (max_cpu) *max_cpu = 0;
  for (pid_t p : pids) {
    rusage u{};
    int status = 0;
    wait4(p, &status, 0, &u);
    cpu += CpuSeconds(u);
    if (max_cpu) *max_cpu = std::max(*max_cpu, CpuSeconds(u));
  }
  pids.clear();
  return cpu;
}

// CPU seconds (user + system, all threads) a live process has used so far.
double LiveCpuSeconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::size_t paren = stat.rfind(')');
  if (paren == std::string::npos) return 0;
  std::istringstream fields(stat.substr(paren + 2));
  std::string field;
  double ticks = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i)
    if (i == 14 || i == 15) ticks += std::stod(field);  // utime, stime
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// Sum of the thread CPU seconds the workers measured inside sample and ΔG
// tasks (TaskResult.cpu_seconds) of a job.
std::pair<double, double> TaskCpuSeconds(storage::JobStore& store, const std::string& job_id) {
  double samples = 0, changes = 0;
  for (const auto& t : store.Tasks(job_id)) {
    v1::TaskResult r;
    r.ParseFromString(t.result);
    (t.kind == v1::TASK_KIND_SAMPLE ? samples : changes) += r.cpu_seconds();
  }
  return {samples, changes};
}

std::string LastLine(const fs::path& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
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
  auto results = RunTasks(c, "noop-bench", payloads, keys);
  return static_cast<double>(results.size()) / Seconds(t0, Clock::now());
}

std::string only;  // --only: run one section
bool Run(const char* section) { return only.empty() || only == section; }

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  CLI::App app{
      "cluster benchmarks (results in docs/benchmarks.md, Cluster): no-op round trips through one "
      "coordinator, per-task overhead, idle workers, blob ingest, speed-up of 2 workers over 1"};
  app.option_defaults()->always_capture_default();
  int tasks = 20000, repeats = 3, blob_mb = 128, idle = 1000, speedup_repeats = -1, overhead_slots = 1;
  std::string job = (fs::path(FABATLAS_BENCH_SOURCE_DIR) / "bench/cluster/data/pawn_small.yaml").string();
  bool fsync_commits = false, no_lease_affinity = false;
  app.add_option("--tasks", tasks, "no-op tasks per throughput run");
  app.add_option("--repeats", repeats, "runs of each measurement");
  app.add_option("--blob-mb", blob_mb, "size of the blob uploaded for the ingest rate, MB");
  app.add_option("--idle", idle, "idle workers connected during the third measurement");
  app.add_option("--speedup-repeats", speedup_repeats,
                 "1-worker/2-worker run pairs for the speed-up (default: --repeats)");
  app.add_option("--overhead-slots", overhead_slots, "slots of the worker in the per-task overhead measurement");
  app.add_option("--job", job, "CPU-bound job file for the speed-up");
  app.add_option("--only", only, "run one section only")
      ->check(CLI::IsMember({"noop", "overhead", "idle", "blob", "speedup"}));
  app.add_flag("--fsync-commits", fsync_commits, "coordinator store fsyncs every commit (synchronous=FULL)");
  app.add_flag("--no-lease-affinity", no_lease_affinity, "lease tasks oldest first, ignoring affinity");
  CLI11_PARSE(app, argc, argv);
  if (speedup_repeats < 0) speedup_repeats = repeats;
  log::Configure({log::Level::kWarn, log::Format::kText});  // the coordinator in this process logs warnings only
  fs::path dir = fs::temp_directory_path() / ("fabatlas_cluster_bench_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);

  coordinator::CoordinatorOptions options;
  options.listen = "127.0.0.1:0";
  options.state_dir = dir / "state";
  options.fsync_commits = fsync_commits;  // synchronous=FULL
  options.lease_affinity = !no_lease_affinity;
  coordinator::Coordinator c(options);
  c.Start();
  std::string target = "127.0.0.1:" + std::to_string(c.port());
  std::vector<pid_t> workers;
  if (Run("noop") || Run("idle")) {
    for (int i = 0; i < 2; ++i) workers.push_back(SpawnWorker(c.port(), 64, dir / ("noop" + std::to_string(i))));
    NoopThroughput(c, 500, 999);  // warm-up: workers connected
  }

  if (Run("noop")) {
    std::vector<double> rates, cpu_us;
    for (int r = 0; r < repeats; ++r) {
      double cpu0 = ProcessCpuSeconds();
      rates.push_back(NoopThroughput(c, tasks, r));
      cpu_us.push_back(1e6 * (ProcessCpuSeconds() - cpu0) / tasks);
    }
    std::printf("noop round trips: %d tasks x %d repeats, 2 workers x 64 slots: median %.0f tasks/s (runs:", tasks,
                repeats, Median(rates));
    for (double x : rates) std::printf(" %.0f", x);
    std::printf("); coordinator CPU per task: median %.0f us\n", Median(cpu_us));
  }

  if (Run("overhead")) {
    // One idle 1-slot worker, long-polling; one no-op task at a time.
    coordinator::CoordinatorOptions o = options;
    o.state_dir = dir / "overhead";
    coordinator::Coordinator oc(o);
    oc.Start();
    std::vector<pid_t> one{SpawnWorker(oc.port(), overhead_slots, dir / "overhead_worker")};
    {
      std::vector<std::string> keys;
      auto payloads = NoopPayloads(20, 99999, &keys);
      RunTasks(oc, "noop-overhead", payloads, keys);  // warm-up: the worker is connected
    }
    const int n = 1000;
    std::vector<double> latencies;
    double cpu0 = ProcessCpuSeconds();
    for (int i = 0; i < n; ++i) {
      std::vector<std::string> keys;
      auto payloads = NoopPayloads(1, 100000 + i, &keys);
      auto t0 = Clock::now();
      RunTasks(oc, "noop-overhead", payloads, keys);
      latencies.push_back(1000.0 * Seconds(t0, Clock::now()));
    }
    double cpu_us = 1e6 * (ProcessCpuSeconds() - cpu0) / n;
    double worker_cpu = StopWorkers(one);
    oc.Shutdown();
    std::sort(latencies.begin(), latencies.end());
    std::printf(
        "coordinator overhead per task (one no-op task at a time, RunTasks -> result, 1 idle worker x %d "
        "slot(s)), %d tasks: p50 %.2f ms, p90 %.2f ms, p99 %.2f ms, max %.2f ms; coordinator CPU %.0f us/task, "
        "worker CPU %.0f us/task\n",
        overhead_slots, n, latencies[n / 2], latencies[n * 9 / 10], latencies[n * 99 / 100], latencies.back(), cpu_us,
        1e6 * worker_cpu / n);
  }

  // Idle workers: own connections (local subchannel pools), Sync with no free slot.
  if (idle > 0 && Run("idle")) {
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
          stubs.push_back(
              v1::WorkerService::NewStub(grpc::CreateCustomChannel(target, grpc::InsecureChannelCredentials(), args)));
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
    std::printf(
        "with %d idle workers connected (%ld idle syncs, %ld failed; idle sync p99 %.2f ms): median %.0f "
        "no-op tasks/s\n",
        idle, syncs.load(), failures.load(), sync_ms.empty() ? 0.0 : sync_ms[sync_ms.size() * 99 / 100], Median(busy));
  }
  StopWorkers(workers);

  // Blob ingest.
  if (Run("blob")) {
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
  if (fs::exists(job) && Run("speedup")) {
    std::vector<double> wall[3], coordinator_cpu[3], worker_cpu[3], busiest_cpu[3], process_cpu[3];
    long long task_count = 0;
    std::printf("speed-up of 2 workers over 1 x 1 slot, %s, lease affinity %s\n", fs::path(job).filename().c_str(),
                options.lease_affinity ? "on" : "off");
    for (int r = 0; r < speedup_repeats; ++r) {
      for (int n : {1, 2}) {
        coordinator::CoordinatorOptions o = options;
        std::string name = std::to_string(n) + "_" + std::to_string(r);
        o.state_dir = dir / ("speedup" + name);
        coordinator::Coordinator sc(o);
        sc.Start();
        // The coordinator's store, read through a connection of its own.
        storage::JobStore state(o.state_dir / "state.db");
        std::vector<pid_t> pids;
        std::vector<fs::path> caches;
        std::int64_t spawned_ms =
            std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
                .count();
        for (int i = 0; i < n; ++i) {
          caches.push_back(dir / ("cpu" + name + "_" + std::to_string(i)));
          pids.push_back(SpawnWorker(sc.port(), 1, caches.back()));
        }
        // Connected (one Sync each) before the job starts.
        while (state.CountWorkers(spawned_ms - 1000) < n) std::this_thread::sleep_for(std::chrono::milliseconds(20));
        coordinator::JobClient client("127.0.0.1:" + std::to_string(sc.port()), {});
        std::vector<double> cpu_start;
        for (pid_t p : pids) cpu_start.push_back(LiveCpuSeconds(p));
        double cpu0 = ProcessCpuSeconds();
        auto t0 = Clock::now();
        std::string id = client.Submit(job);
        auto s = client.Watch(id, [](const v1::JobStatus&) { return true; });
        wall[n].push_back(Seconds(t0, Clock::now()));
        coordinator_cpu[n].push_back(ProcessCpuSeconds() - cpu0);
        double job_cpu = 0, busiest = 0;
        for (std::size_t i = 0; i < pids.size(); ++i) {
          double used = LiveCpuSeconds(pids[i]) - cpu_start[i];
          job_cpu += used;
          busiest = std::max(busiest, used);
        }
        worker_cpu[n].push_back(job_cpu);
        busiest_cpu[n].push_back(busiest);
        process_cpu[n].push_back(StopWorkers(pids));
        task_count = s.tasks_total();
        auto [sample_cpu, change_cpu] = TaskCpuSeconds(state, id);
        double subtree_seconds = 0;
        std::int64_t subtree_computations = 0;
        for (const auto& row : state.Subtrees(id)) {
          subtree_seconds += row.seconds_sum;
          subtree_computations += row.seconds_count;
        }
        std::printf(
            "  run %d, %d worker(s): %.2f s wall; workers CPU during the job %.2f s (busiest %.2f s; "
            "inside tasks: samples %.2f s, ΔG %.2f s; whole processes %.2f s); coordinator CPU %.2f s; "
            "%lld subtrees computed; %lld tasks, %s\n",
            r, n, wall[n].back(), job_cpu, busiest, sample_cpu, change_cpu, process_cpu[n].back(),
            coordinator_cpu[n].back(), static_cast<long long>(subtree_computations),
            static_cast<long long>(s.tasks_total()), coordinator::JobStateName(s.state()).c_str());
        for (const auto& cache : caches)
          std::printf("    %s\n", LastLine(cache.parent_path() / (cache.filename().string() + ".log")).c_str());
        std::fflush(stdout);
        sc.Shutdown();
      }
      std::printf("  pair %d: wall ratio %.2fx, CPU ratio %.2fx\n", r, wall[1][r] / wall[2][r],
                  busiest_cpu[1][r] / busiest_cpu[2][r]);
    }
    std::vector<double> ratios, cpu_ratios;
    for (int r = 0; r < speedup_repeats; ++r) {
      ratios.push_back(wall[1][r] / wall[2][r]);
      cpu_ratios.push_back(busiest_cpu[1][r] / busiest_cpu[2][r]);
    }
    std::printf(
        "%s, %lld tasks, %d pairs: wall-time speed-up median %.2fx (1 worker %.2f s, 2 workers %.2f s); "
        "CPU-time speed-up median %.2fx (1 worker %.2f s, busier of 2 %.2f s, both %.2f s); coordinator "
        "CPU per task %.2f ms (1 worker) / %.2f ms (2 workers)\n",
        fs::path(job).filename().c_str(), task_count, speedup_repeats, Median(ratios), Median(wall[1]), Median(wall[2]),
        Median(cpu_ratios), Median(busiest_cpu[1]), Median(busiest_cpu[2]), Median(worker_cpu[2]),
        1000.0 * Median(coordinator_cpu[1]) / std::max(1LL, task_count),
        1000.0 * Median(coordinator_cpu[2]) / std::max(1LL, task_count));
  }
  fs::remove_all(dir);
  return 0;
}
