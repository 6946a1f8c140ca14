// A job client for the cluster tests: JobService calls on a loopback
// coordinator and a poll that waits for a job to end (needs
// fabatlas_coordinator).
#pragma once

#include <chrono>
#include <functional>
#include <string>
#include <thread>

#include "fabatlas/coordinator/job_client.h"
#include "fabatlas/error.h"

namespace fabatlas::cluster_test {

inline coordinator::JobClient Client(int port, const std::string& token = "") {
  protocol::ClientSecurity security;
  security.token = token;
  return coordinator::JobClient("127.0.0.1:" + std::to_string(port), security, std::chrono::seconds(5));
}

// Polls until the job ends (tolerating a coordinator that is down) or the
// timeout passes; calls between() after each poll.
inline v1::JobStatus WaitForJob(const std::function<int()>& port, const std::string& id, std::chrono::seconds timeout,
                                const std::function<void(const v1::JobStatus&)>& between = {}) {
  auto until = std::chrono::steady_clock::now() + timeout;
  v1::JobStatus last;
  while (std::chrono::steady_clock::now() < until) {
    try {
      last = Client(port()).Status(id);
      if (last.state() >= v1::JOB_STATE_SUCCEEDED) return last;
    } catch (const InputError&) {
    }
    if (between) between(last);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return last;
}

}  // namespace fabatlas::cluster_test
