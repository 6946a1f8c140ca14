// fabatlas/testing/command_run.h — the fabatlas command as a user runs it
// from a shell: its exit status, stdout and stderr apart.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "fabatlas/testing/paths.h"

namespace fabatlas::testing {

struct CommandRun {
  int status = -1;  // exit status; -1 when killed by a signal
  std::string out, err;
};

// Runs `build/bin/fabatlas ARGS` through /bin/sh (ARGS is shell text: quote
// paths with spaces), in `cwd` when given, so relative paths are the user's.
inline CommandRun Fabatlas(const std::string& args, const std::filesystem::path& cwd = {}) {
  static std::atomic<int> counter{0};
  const std::filesystem::path err_path =
      std::filesystem::temp_directory_path() /
      ("fabatlas-cli-err-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::string cmd = (BinDir() / "fabatlas").string() + " " + args + " 2>'" + err_path.string() + "'";
  if (!cwd.empty()) cmd = "cd '" + cwd.string() + "' && " + cmd;
  CommandRun r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  const int status = ::pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream e(err_path);
  r.err.assign(std::istreambuf_iterator<char>(e), {});
  std::filesystem::remove(err_path);
  return r;
}

}  // namespace fabatlas::testing
