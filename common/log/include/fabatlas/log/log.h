// fabatlas/log/log.h — the operator's log: one line per state change an
// operator cares about, written to stderr (journald and `kubectl logs` read
// it there), flushed line by line so a killed process leaves whole lines.
//
// A line is an event name (snake_case, e.g. "job_submitted") plus fields
// naming the ids involved and the numbers that matter:
//   text: 2026-11-24T01:40:00.123Z info job_submitted job=1a2b3c design=pawn
//   json: {"ts":"2026-11-24T01:40:00.123Z","level":"info","event":"job_submitted","job":"1a2b3c","design":"pawn"}
// JSON lines are single objects (one per line); field values are strings,
// numbers or booleans. Times are UTC. Event names and their fields are listed
// in docs/operations.md ("Logs").
//
// Usage:
//   log::Info("worker_joined", {{"worker", id}, {"slots", 4}});
//   log::Error("state_write_failed", {{"path", p}, {"error", e.what()}});
//
// Threading: Configure once at start-up, before other threads log; Write and
// the level helpers are thread-safe (one line is never interleaved with
// another).
#pragma once

#include <concepts>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>

namespace fabatlas::log {

enum class Level { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3, kOff = 4 };
enum class Format { kText, kJson };

struct LogOptions {
  Level level = Level::kInfo;     // lines below this level are dropped
  Format format = Format::kText;  // text for people, json for log pipelines
};

// Applies the options to every later line. Without a call: info, text.
void Configure(const LogOptions& options);

// "debug" | "info" | "warn" | "error" | "off"; throws InputError naming
// `option` (e.g. "--log-level") and the accepted values otherwise.
Level ParseLevel(std::string_view text, std::string_view option = "--log-level");
// "text" | "json"; throws InputError like ParseLevel.
Format ParseFormat(std::string_view text, std::string_view option = "--log-format");

// One key=value field of a line. Strings are quoted (escaped) in JSON and
// quoted in text when they contain spaces, '=' or quotes.
struct Field {
  Field(std::string_view k, std::string_view v) : key(k), value(v), quoted(true) {}
  Field(std::string_view k, const char* v) : key(k), value(v ? v : ""), quoted(true) {}
  Field(std::string_view k, const std::string& v) : key(k), value(v), quoted(true) {}
  Field(std::string_view k, bool v) : key(k), value(v ? "true" : "false"), quoted(false) {}
  template <std::integral T>
  requires(!std::same_as<T, bool>) Field(std::string_view k, T v) : key(k), value(std::to_string(v)), quoted(false) {}
  Field(std::string_view k, double v);  // shortest round-trip text; NaN/inf as strings

  std::string key, value;
  bool quoted;
};

// True when a line of this level would be written.
bool Enabled(Level level);

// Writes one line: the event with its fields, in the configured format.
void Write(Level level, std::string_view event, std::initializer_list<Field> fields = {});

inline void Debug(std::string_view event, std::initializer_list<Field> fields = {}) {
  Write(Level::kDebug, event, fields);
}
inline void Info(std::string_view event, std::initializer_list<Field> fields = {}) {
  Write(Level::kInfo, event, fields);
}
inline void Warn(std::string_view event, std::initializer_list<Field> fields = {}) {
  Write(Level::kWarn, event, fields);
}
inline void Error(std::string_view event, std::initializer_list<Field> fields = {}) {
  Write(Level::kError, event, fields);
}

// The line Write would emit (no trailing newline), for tests and for
// callers that print elsewhere. `ts_ms` is Unix time in milliseconds.
std::string FormatLine(Format format, Level level, std::int64_t ts_ms, std::string_view event,
                       std::initializer_list<Field> fields);

}  // namespace fabatlas::log
