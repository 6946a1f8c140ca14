// The model is described in job_eta.h.
#include "fabatlas/coordinator/job_eta.h"

#include <algorithm>

namespace fabatlas::coordinator {

namespace {

// CPU seconds of work per wall second between the newest point at least
// `window` seconds old (the oldest when none is) and now.
double RateOf(const std::vector<EtaProgress>& progress, double window, double overhead) {
  if (progress.empty()) return 0;
  std::size_t from = 0;
  for (std::size_t i = 0; i < progress.size(); ++i)
    if (progress[i].seconds_ago >= window) from = i;
  const EtaProgress &a = progress[from], &b = progress.back();
  if (a.seconds_ago <= 0) return 0;
  const double work = (b.cpu_seconds - a.cpu_seconds) + overhead * (b.tasks - a.tasks);
  return std::max(work, 0.0) / a.seconds_ago;
}

}  // namespace

JobEta EstimateJobEta(const JobEtaInput& in, const JobEtaOptions& options) {
  JobEta eta;
  // Sample batch sizes S_0, S_1, ...; ΔG per new sample h of each ΔG batch,
  // with the sample batch it follows.
  std::vector<double> s;
  std::vector<std::pair<std::size_t, double>> h;  // (index into s, G / S)
  // Evaluator CPU seconds per task of each kind ([1] sample, [0] ΔG) in the
  // last finished batch of that kind.
  double cpu_per[2] = {0, 0};
  for (const EtaBatch& b : in.batches) {
    if (b.samples) {
      s.push_back(b.tasks);
    } else if (!s.empty() && s.back() > 0) {
      h.emplace_back(s.size() - 1, b.tasks / s.back());
    }
    if (b.tasks > 0 && b.cpu_seconds > 0) cpu_per[b.samples] = b.cpu_seconds / b.tasks;
  }
  double sampled = 0;
  for (double n : s) sampled += n;

  const bool publishing = in.publishing_seconds >= 0;
  const EtaBatch* running = !publishing && !in.batches.empty() ? &in.batches.back() : nullptr;
  if (running && running->cpu_seconds <= 0 && running->tasks > 0 && in.running_done.tasks >= 1) {
    // The running batch's own CPU per task, weighed by the share of it done.
    const double own = in.running_done.cpu_seconds / in.running_done.tasks;
    const double done = std::clamp(running->tasks - in.running_left, 0.0, running->tasks);
    const double w = done / running->tasks;
    double& c = cpu_per[running->samples];
    c = c > 0 ? (1 - w) * c + w * own : own;
  }
  const double o = options.overhead_cpu_seconds_per_task;
  const double cs = (cpu_per[1] > 0 ? cpu_per[1] : cpu_per[0]) + o;  // work per sample task
  const double cg = (cpu_per[0] > 0 ? cpu_per[0] : cpu_per[1]) + o;  // work per ΔG task

  // ΔG tasks per new sample for the rounds to come.
  double hn = static_cast<double>(std::max(in.dimensions, 1));
  std::vector<double> split_h;  // h of split rounds (after S_1, S_2, ...)
  for (const auto& [k, v] : h)
    if (k >= 1) split_h.push_back(v);
  if (split_h.size() >= 2 && split_h[split_h.size() - 2] > 0) {
    const double trend = std::clamp(split_h.back() / split_h[split_h.size() - 2], 1 / 1.25, 1.25);
    hn = split_h.back() * trend;
  } else if (split_h.size() == 1) {
    hn = split_h.back();
  } else if (!h.empty()) {
    hn = h.back().second * options.first_split_dg_per_sample_factor;
  }

  double work = 0;  // CPU seconds of work still to do before publishing
  double budget = in.max_samples - sampled;
  if (!publishing && !s.empty()) {
    if (running) work += in.running_left * (running->samples ? cs : cg);
    // The running round's ΔG batch, when its sample batch runs now.
    if (running && running->samples) work += s.back() * hn * cg;
    const double g = s.size() >= 3 && s[s.size() - 2] > 0 ? s.back() / s[s.size() - 2] : options.first_growth;
    double last = s.back();
    for (int depth = static_cast<int>(s.size()); depth <= in.max_depth && budget >= 1; ++depth) {
      const double next = std::min(last * g, budget);
      if (next < 1) break;
      work += next * cs + next * hn * cg;
      budget -= next;
      last = next;
    }
  }
  eta.predicted_samples = in.max_samples - std::max(budget, 0.0);
  if (publishing) eta.predicted_samples = sampled;
  eta.publish_seconds = options.publish_seconds_per_sample * eta.predicted_samples;
  if (publishing) {
    eta.known = true;
    eta.seconds = std::max(eta.publish_seconds - in.publishing_seconds, 0.0);
    return eta;
  }
  eta.work_cpu_seconds = work;
  eta.rate = RateOf(in.progress, options.rate_window_seconds, o);
  if (eta.rate <= 0 || cs <= o) return eta;  // no task's CPU or no rate yet
  eta.known = true;
  eta.seconds = work / eta.rate + eta.publish_seconds;
  return eta;
}

}  // namespace fabatlas::coordinator
