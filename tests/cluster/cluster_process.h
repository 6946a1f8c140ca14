// Real processes for the cluster tests: a coordinator and workers started
// from the build's bin/ directory, signalled and reaped by pid.
#pragma once

#include "fabatlas/testing/paths.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <fcntl.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

namespace fabatlas::cluster_test {

namespace fs = std::filesystem;

inline fs::path BinDir() {
  // The test binary lives in bin/ beside the programs it starts.
  const char* dir = std::getenv("FABATLAS_BIN_DIR");
  if (dir && fs::exists(fs::path(dir) / "fabatlas-coordinator")) return dir;
  return fs::read_symlink("/proc/self/exe").parent_path();
}
inline fs::path SourceDir() { return fabatlas::testing::SourceDir(); }

inline fs::path FreshDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("fabatlas_cluster_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Starts argv[0] with the rest as arguments, stdout and stderr to `log`.
// The child dies with the test (PR_SET_PDEATHSIG).
inline pid_t Spawn(const std::vector<std::string>& argv, const fs::path& log) {
  // Everything the child needs is prepared before fork: after fork only
  // async-signal-safe calls (other threads may hold the allocator's locks).
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::string log_path = log.string();
  pid_t pid = ::fork();
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
    }
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  return pid;
}

// Waits up to timeout for the process; returns its exit status, or -1 on
// timeout, or 128 + signal when killed.
inline int WaitExit(pid_t pid, std::chrono::milliseconds timeout) {
  auto until = std::chrono::steady_clock::now() + timeout;
  while (true) {  // checks at least once, also with a zero timeout
    int status = 0;
    pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    if (std::chrono::steady_clock::now() >= until) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

inline void KillAndReap(pid_t pid) {
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
}

// A TCP port nothing listens on now (bound to 0, read back, released; a
// race with another process is possible but unlikely); 0 on failure.
inline int FreePort() {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  socklen_t len = sizeof addr;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    ::close(fd);
    return 0;
  }
  ::close(fd);
  return ntohs(addr.sin_port);
}

inline std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

struct CoordinatorProcess {
  pid_t pid = -1;
  int port = 0;
  int exit_status = -1;  // when it ended before listening (then reaped), its exit status
};

// Starts fabatlas-coordinator on 127.0.0.1:port (0 = any) and waits for it
// to listen. `env`: NAME=VALUE settings added to its environment (through
// /usr/bin/env, so this process's environment stays as it is).
inline CoordinatorProcess StartCoordinator(const fs::path& state, int port, const std::vector<std::string>& extra = {},
                                           const std::vector<std::string>& env = {}) {
  fs::path port_file = state / "port";
  fs::create_directories(state);
  fs::remove(port_file);
  std::vector<std::string> argv;
  if (!env.empty()) {
    argv.push_back("/usr/bin/env");
    argv.insert(argv.end(), env.begin(), env.end());
  }
  argv.insert(argv.end(),
              {(BinDir() / "fabatlas-coordinator").string(), "--listen", "127.0.0.1:" + std::to_string(port),
               "--state-dir", state.string(), "--port-file", port_file.string()});
  argv.insert(argv.end(), extra.begin(), extra.end());
  CoordinatorProcess c;
  c.pid = Spawn(argv, state / "coordinator.log");
  for (int i = 0; i < 500 && c.port == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    std::string text = ReadText(port_file);
    if (!text.empty()) c.port = std::atoi(text.c_str());
    if ((c.exit_status = WaitExit(c.pid, std::chrono::milliseconds(0))) != -1) break;
  }
  return c;
}

inline pid_t StartWorker(int port, const fs::path& dir, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> argv = {(BinDir() / "fabatlas-worker").string(), "--coordinator",
                                   "127.0.0.1:" + std::to_string(port), "--cache-dir", (dir / "cache").string()};
  argv.insert(argv.end(), extra.begin(), extra.end());
  fs::create_directories(dir);
  return Spawn(argv, dir / "worker.log");
}

}  // namespace fabatlas::cluster_test
