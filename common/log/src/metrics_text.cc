// Prometheus text exposition (metrics_text.h).
#include "fabatlas/log/metrics_text.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>

namespace fabatlas::log {

namespace {

std::string Number(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "+Inf" : "-Inf";
  char buf[40];
  if (v == std::floor(v) && std::fabs(v) < 1e15)
    std::snprintf(buf, sizeof buf, "%.0f", v);
  else
    std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string LabelText(const Labels& labels) {
  if (labels.empty()) return "";
  std::string out = "{";
  for (std::size_t i = 0; i < labels.size(); ++i) {
    out += (i ? "," : "") + labels[i].first + "=\"";
    for (char c : labels[i].second) {
      if (c == '\\' || c == '"') out += '\\';
      if (c == '\n') {
        out += "\\n";
        continue;
      }
      out += c;
    }
    out += '"';
  }
  return out + "}";
}

}  // namespace

void MetricsText::Declare(const std::string& name, const std::string& help, const char* type) {
  if (!declared_.insert(name).second) return;
  text_ += "# HELP " + name + " " + help + "\n# TYPE " + name + " " + type + "\n";
}

void MetricsText::Sample(const std::string& name, double value, const Labels& labels) {
  text_ += name + LabelText(labels) + " " + Number(value) + "\n";
}

void MetricsText::Counter(const std::string& name, const std::string& help, double value, const Labels& labels) {
  Declare(name, help, "counter");
  Sample(name, value, labels);
}

void MetricsText::Gauge(const std::string& name, const std::string& help, double value, const Labels& labels) {
  Declare(name, help, "gauge");
  Sample(name, value, labels);
}

void DurationHistogram::Observe(const std::string& label_value, double seconds) {
  std::lock_guard lock(mu_);
  Series& s = series_[label_value];
  for (std::size_t i = 0; i < kBuckets.size(); ++i)
    if (seconds <= kBuckets[i]) ++s.counts[i];
  ++s.count;
  s.sum += seconds;
}

void DurationHistogram::Write(MetricsText& m, const std::string& name, const std::string& help) const {
  m.Declare(name, help, "histogram");
  std::lock_guard lock(mu_);
  for (const auto& [value, s] : series_) {
    for (std::size_t i = 0; i < kBuckets.size(); ++i)
      m.Sample(name + "_bucket", static_cast<double>(s.counts[i]), {{label_, value}, {"le", Number(kBuckets[i])}});
    m.Sample(name + "_bucket", static_cast<double>(s.count), {{label_, value}, {"le", "+Inf"}});
    m.Sample(name + "_sum", s.sum, {{label_, value}});
    m.Sample(name + "_count", static_cast<double>(s.count), {{label_, value}});
  }
}

std::int64_t ResidentMemoryBytes() {
  std::ifstream in("/proc/self/statm");
  std::int64_t size = 0, resident = 0;
  if (!(in >> size >> resident)) return 0;
  return resident * static_cast<std::int64_t>(::sysconf(_SC_PAGESIZE));
}

}  // namespace fabatlas::log
