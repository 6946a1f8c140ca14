// The operator's log lines (fabatlas/log/log.h): JSON lines are single JSON
// objects a standard parser reads back field for field; text lines keep one
// event per line whatever the values hold.
#include "fabatlas/log/log.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>

#include "fabatlas/error.h"

namespace fabatlas::log {
namespace {

TEST(LogLine, JsonLineParsesBackWithEveryField) {
  // 2026-11-24T01:40:00.123Z as Unix milliseconds (date -u -d ... +%s%3N).
  const std::int64_t ts = 1795484400123;
  std::string line = FormatLine(Format::kJson, Level::kWarn, ts, "lease_expired",
                                {{"task", "ab\"c\\d\n"},
                                 {"worker", "w-1"},
                                 {"attempt", 3},
                                 {"ratio", 0.1},
                                 {"quarantined", false},
                                 {"bytes", std::int64_t{1} << 40}});
  EXPECT_EQ(line.find('\n'), std::string::npos);
  nlohmann::json j = nlohmann::json::parse(line);
  EXPECT_EQ(j["ts"], "2026-11-24T01:40:00.123Z");
  EXPECT_EQ(j["level"], "warn");
  EXPECT_EQ(j["event"], "lease_expired");
  EXPECT_EQ(j["task"], "ab\"c\\d\n");
  EXPECT_EQ(j["worker"], "w-1");
  EXPECT_EQ(j["attempt"], 3);
  EXPECT_EQ(j["ratio"].get<double>(), 0.1);  // shortest text that reads back exactly
  EXPECT_EQ(j["quarantined"], false);
  EXPECT_EQ(j["bytes"].get<std::int64_t>(), std::int64_t{1} << 40);
}

TEST(LogLine, NonFiniteNumbersStayValidJson) {
  std::string line = FormatLine(Format::kJson, Level::kInfo, 0, "x",
                                {{"a", std::numeric_limits<double>::quiet_NaN()}, {"b", -INFINITY}});
  nlohmann::json j = nlohmann::json::parse(line);
  EXPECT_EQ(j["ts"], "1970-01-01T00:00:00.000Z");
  EXPECT_EQ(j["a"], "NaN");
  EXPECT_EQ(j["b"], "-Infinity");
}

TEST(LogLine, TextLineQuotesValuesWithSpaces) {
  std::string line = FormatLine(Format::kText, Level::kError, 0, "job_failed",
                                {{"job", "1a2b"}, {"error", "disk full: /var/lib"}, {"n", 2}});
  EXPECT_EQ(line, "1970-01-01T00:00:00.000Z error job_failed job=1a2b error=\"disk full: /var/lib\" n=2");
  EXPECT_EQ(FormatLine(Format::kText, Level::kInfo, 0, "e", {{"s", ""}}), "1970-01-01T00:00:00.000Z info e s=\"\"");
}

TEST(LogOptions, ParseNamesTheOptionAndTheAcceptedValues) {
  EXPECT_EQ(ParseLevel("debug"), Level::kDebug);
  EXPECT_EQ(ParseLevel("warn"), Level::kWarn);
  EXPECT_EQ(ParseFormat("json"), Format::kJson);
  try {
    ParseLevel("loud");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "--log-level: 'loud' is not a log level (debug, info, warn, error, off)");
  }
  EXPECT_THROW(ParseFormat("xml"), InputError);
}

TEST(LogOptions, LevelFiltersLines) {
  Configure({Level::kWarn, Format::kJson});
  EXPECT_FALSE(Enabled(Level::kInfo));
  EXPECT_TRUE(Enabled(Level::kWarn));
  EXPECT_TRUE(Enabled(Level::kError));
  Configure({Level::kOff, Format::kText});
  EXPECT_FALSE(Enabled(Level::kError));
  Configure({});
  EXPECT_TRUE(Enabled(Level::kInfo));
  EXPECT_FALSE(Enabled(Level::kDebug));
}

}  // namespace
}  // namespace fabatlas::log
