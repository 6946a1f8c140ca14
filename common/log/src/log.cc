// The operator's log (log.h) over an spdlog stderr sink: fabatlas formats the
// whole line (so text and JSON carry the same fields), spdlog filters by
// level, serialises writers and flushes every line.
#include "fabatlas/log/log.h"

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>

#include "fabatlas/error.h"

namespace fabatlas::log {

namespace {

std::atomic<int> g_level{static_cast<int>(Level::kInfo)};
std::atomic<int> g_format{static_cast<int>(Format::kText)};

spdlog::logger& Logger() {
  static const std::shared_ptr<spdlog::logger> logger = [] {
    auto l = std::make_shared<spdlog::logger>("fabatlas", std::make_shared<spdlog::sinks::stderr_sink_mt>());
    l->set_pattern("%v");
    l->set_level(spdlog::level::trace);  // filtered by g_level before formatting
    l->flush_on(spdlog::level::trace);
    return l;
  }();
  return *logger;
}

const char* LevelName(Level level) {
  switch (level) {
    case Level::kDebug:
      return "debug";
    case Level::kInfo:
      return "info";
    case Level::kWarn:
      return "warn";
    case Level::kError:
      return "error";
    case Level::kOff:
      return "off";
  }
  return "info";
}

std::string Timestamp(std::int64_t ts_ms) {
  std::time_t secs = static_cast<std::time_t>(ts_ms / 1000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char buf[96];  // room for every field at int's widest, as snprintf's check asks
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ts_ms % 1000));
  return buf;
}

void AppendJsonString(std::string& out, std::string_view s) {
  out += '"';
  for (unsigned char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  out += '"';
}

// Text values: bare when they are one word, else quoted like JSON (so a
// line stays one line and splits unambiguously on spaces).
void AppendTextValue(std::string& out, const Field& f) {
  bool bare = !f.value.empty();
  for (unsigned char c : f.value)
    if (c <= ' ' || c == '"' || c == '=' || c == '\\') bare = false;
  if (bare || !f.quoted)
    out += f.value;
  else
    AppendJsonString(out, f.value);
}

}  // namespace

Field::Field(std::string_view k, double v) : key(k), quoted(false) {
  if (!std::isfinite(v)) {
    value = std::isnan(v) ? "NaN" : (v > 0 ? "Infinity" : "-Infinity");
    quoted = true;
    return;
  }
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  // The shortest of %.6g .. %.17g that reads back exactly.
  for (int precision = 6; precision < 17; ++precision) {
    char shorter[40];
    std::snprintf(shorter, sizeof shorter, "%.*g", precision, v);
    if (std::strtod(shorter, nullptr) == v) {
      value = shorter;
      return;
    }
  }
  value = buf;
}

void Configure(const LogOptions& options) {
  g_level = static_cast<int>(options.level);
  g_format = static_cast<int>(options.format);
}

Level ParseLevel(std::string_view text, std::string_view option) {
  for (Level l : {Level::kDebug, Level::kInfo, Level::kWarn, Level::kError, Level::kOff})
    if (text == LevelName(l)) return l;
  if (text == "warning") return Level::kWarn;
  throw InputError(std::string(option) + ": '" + std::string(text) +
                   "' is not a log level (debug, info, warn, error, off)");
}

Format ParseFormat(std::string_view text, std::string_view option) {
  if (text == "text") return Format::kText;
  if (text == "json") return Format::kJson;
  throw InputError(std::string(option) + ": '" + std::string(text) + "' is not a log format (text, json)");
}

bool Enabled(Level level) { return level != Level::kOff && static_cast<int>(level) >= g_level.load(); }

std::string FormatLine(Format format, Level level, std::int64_t ts_ms, std::string_view event,
                       std::initializer_list<Field> fields) {
  std::string line;
  line.reserve(96 + 24 * fields.size());
  if (format == Format::kJson) {
    line += "{\"ts\":\"" + Timestamp(ts_ms) + "\",\"level\":\"" + LevelName(level) + "\",\"event\":";
    AppendJsonString(line, event);
    for (const Field& f : fields) {
      line += ',';
      AppendJsonString(line, f.key);
      line += ':';
      if (f.quoted)
        AppendJsonString(line, f.value);
      else
        line += f.value;
    }
    line += '}';
  } else {
    line += Timestamp(ts_ms) + " " + LevelName(level) + " " + std::string(event);
    for (const Field& f : fields) {
      line += ' ' + f.key + '=';
      AppendTextValue(line, f);
    }
  }
  return line;
}

void Write(Level level, std::string_view event, std::initializer_list<Field> fields) {
  if (!Enabled(level)) return;
  std::int64_t now =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count();
  std::string line = FormatLine(static_cast<Format>(g_format.load()), level, now, event, fields);
  Logger().log(spdlog::level::info, spdlog::string_view_t(line.data(), line.size()));
}

}  // namespace fabatlas::log
