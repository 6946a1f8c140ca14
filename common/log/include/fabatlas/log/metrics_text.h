// fabatlas/log/metrics_text.h — Prometheus text exposition (format 0.0.4)
// for the coordinator's and the worker's /metrics pages, following the
// Prometheus naming conventions: counters end in _total, units in the name
// (_seconds, _bytes), label values lower_snake_case.
//
//   MetricsText m;
//   m.Counter("fabatlas_tasks_completed_total", "Results accepted.", 42);
//   m.Gauge("fabatlas_workers", "Connected workers.", 3);
//   m.Gauge("fabatlas_tasks", "Tasks by state.", 7, {{"state", "queued"}});
//   histogram.Write(m, "fabatlas_task_duration_seconds", "Task wall time.");
//   std::string page = m.text();
//
// HELP and TYPE are written once per metric name, before its first sample.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace fabatlas::log {

using Labels = std::vector<std::pair<std::string, std::string>>;

class MetricsText {
 public:
  void Counter(const std::string& name, const std::string& help, double value, const Labels& labels = {});
  void Gauge(const std::string& name, const std::string& help, double value, const Labels& labels = {});
  // One sample line without HELP/TYPE handling (histogram buckets).
  void Sample(const std::string& name, double value, const Labels& labels = {});
  // Writes HELP and TYPE for `name` unless already written.
  void Declare(const std::string& name, const std::string& help, const char* type);
  const std::string& text() const { return text_; }

 private:
  std::string text_;
  std::set<std::string> declared_;
};

// Cumulative histograms of durations in seconds, one per label value (e.g.
// per task kind), with fixed buckets from 5 ms to 10 min. Thread-safe.
class DurationHistogram {
 public:
  static constexpr std::array<double, 14> kBuckets = {0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5,
                                                      1,     2.5,  5,     10,   30,  60,   600};
  explicit DurationHistogram(std::string label) : label_(std::move(label)) {}
  void Observe(const std::string& label_value, double seconds);
  // _bucket{le=...}, _sum and _count lines for every label value seen.
  void Write(MetricsText& m, const std::string& name, const std::string& help) const;

 private:
  struct Series {
    std::array<std::uint64_t, kBuckets.size()> counts{};
    std::uint64_t count = 0;
    double sum = 0;
  };
  std::string label_;
  mutable std::mutex mu_;
  std::map<std::string, Series> series_;
};

// Resident set size of this process in bytes (/proc/self/statm), 0 when unknown.
std::int64_t ResidentMemoryBytes();

}  // namespace fabatlas::log
