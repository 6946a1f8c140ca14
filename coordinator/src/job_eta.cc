// The model is described in job_eta.h.
#include "fabatlas/coordinator/job_eta.h"

#include <algorithm>

namespace fabatlas::coordinator {

JobEta EstimateJobEta(const JobEtaInput& in, const JobEtaOptions& options) {
  JobEta eta;
  // Sample batch sizes S_0, S_1, ...; ΔG per new sample h of each ΔG batch,
  // with the sample batch it follows.
  std::vector<double> s;
  std::vector<std::pair<std::size_t, double>> h;  // (index into s, G / S)
  // Per kind ([1] sample, [0] ΔG): evaluator CPU seconds per task of the
  // last batch whose results carry it (replayed ones too: it is the
  // evaluation's own), wall seconds per task of the last batch that ran;
  // and the load factor (batch wall seconds per evaluator CPU second) of
  // the last batch that ran.
  double cpu_per[2] = {0, 0}, wall_per[2] = {0, 0}, load = 0;
  for (const EtaBatch& b : in.batches) {
    if (b.samples) {
      s.push_back(b.tasks);
    } else if (!s.empty() && s.back() > 0) {
      h.emplace_back(s.size() - 1, b.tasks / s.back());
    }
    if (b.tasks <= 0) continue;
    if (b.cpu_seconds > 0) cpu_per[b.samples] = b.cpu_seconds / b.tasks;
    if (b.seconds > 0) {
      wall_per[b.samples] = b.seconds / b.tasks;
      load = b.cpu_seconds > 0 ? b.seconds / b.cpu_seconds : 0;
    }
  }
  double sampled = 0;
  for (double n : s) sampled += n;

  const bool publishing = in.publishing_seconds >= 0;
  const EtaBatch* running = !publishing && !in.batches.empty() ? &in.batches.back() : nullptr;
  if (running && running->seconds <= 0 && running->tasks > 0) {
    const double done = std::clamp(running->tasks - in.running_left, 0.0, running->tasks);
    if (in.running_seconds > 0 && done >= 1) {
      const double w = done / running->tasks;
      const auto blend = [w](double last, double live) { return last > 0 ? (1 - w) * last + w * live : live; };
      const int k = running->samples;
      wall_per[k] = blend(wall_per[k], in.running_seconds / done);
      if (cpu_per[k] > 0) load = blend(load, in.running_seconds / (done * cpu_per[k]));
    }
  }
  double t[2];
  for (int k : {0, 1}) t[k] = cpu_per[k] > 0 && load > 0 ? cpu_per[k] * load : wall_per[k];
  double ts = t[1] > 0 ? t[1] : t[0], tg = t[0] > 0 ? t[0] : t[1];

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

  double future = 0;  // wall seconds of batches after the running one
  double budget = in.max_samples - sampled;
  if (!publishing && !s.empty()) {
    // The running round's ΔG batch, when its sample batch runs now.
    if (running && running->samples) future += s.back() * hn * tg;
    const double g = s.size() >= 3 && s[s.size() - 2] > 0 ? s.back() / s[s.size() - 2] : options.first_growth;
    double last = s.back();
    for (int depth = static_cast<int>(s.size()); depth <= in.max_depth && budget >= 1; ++depth) {
      const double next = std::min(last * g, budget);
      if (next < 1) break;
      future += next * ts + next * hn * tg;
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
  if (ts <= 0) return eta;  // no batch has run yet: nothing to scale by
  eta.known = true;
  const double running_rest = running ? in.running_left * (running->samples ? ts : tg) : 0;
  eta.seconds = running_rest + future + eta.publish_seconds;
  return eta;
}

}  // namespace fabatlas::coordinator
