// The artifact's SQLite file: table checksums and column encodings
// (artifact_file.h).
#include "artifact_file.h"

#include <cstring>

#include "fabatlas/sampling/point_key_text.h"
#include "fabatlas/sha256.h"

namespace fabatlas::artifact::format {

std::string SamplesTableSql(int dimensions) {
  std::string sql = "CREATE TABLE samples (id INTEGER PRIMARY KEY, key TEXT NOT NULL UNIQUE";
  for (int d = 0; d < dimensions; ++d) sql += ", u" + std::to_string(d) + " REAL NOT NULL";
  return sql + ", valid INTEGER NOT NULL, failure TEXT NOT NULL);";
}

namespace {

// SHA-256 fed in pieces (the canonical content of a table with cache
// entries is as large as the artifact; only ~1 MiB of it is held at a time).
class Sha256Stream {
 public:
  std::string& buffer() { return buffer_; }
  // Hashes the buffer when it holds at least `min_bytes`.
  void Flush(std::size_t min_bytes = 1 << 20) {
    if (buffer_.size() < min_bytes) return;
    sha_.Update(buffer_);
    buffer_.clear();
  }
  std::string Hex() {
    Flush(0);
    return sha_.Hex();
  }

 private:
  Sha256 sha_;
  std::string buffer_;
};

}  // namespace

std::string TableChecksum(Db& db, const TableOrder& t) {
  Stmt s(db, std::string("SELECT * FROM ") + t.table + " ORDER BY " + t.order);
  Sha256Stream sha;
  std::string& canonical = sha.buffer();
  auto put64 = [&](std::uint64_t v) {
    for (int i = 0; i < 8; ++i) canonical.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  };
  while (s.Next()) {
    for (int c = 0; c < s.ColumnCount(); ++c) {
      switch (s.ColumnType(c)) {
        case SQLITE_NULL:
          canonical.push_back('N');
          break;
        case SQLITE_INTEGER:
          canonical.push_back('I');
          put64(static_cast<std::uint64_t>(s.ColumnInt(c)));
          break;
        case SQLITE_FLOAT: {
          canonical.push_back('R');
          double d = s.ColumnReal(c);
          std::uint64_t bits;
          std::memcpy(&bits, &d, 8);
          put64(bits);
          break;
        }
        default: {
          canonical.push_back(s.ColumnType(c) == SQLITE_TEXT ? 'T' : 'B');
          std::string v = s.ColumnText(c);
          put64(v.size());
          canonical += v;
        }
      }
    }
    sha.Flush();
  }
  return sha.Hex();
}

std::vector<std::int64_t> SplitInts(const std::string& text, const char* what) {
  auto ints = sampling::ParsePointKeyText(text);
  if (!ints) throw Corrupt(std::string("malformed ") + what + " '" + text + "'");
  return *ints;
}

const char* StopName(sampling::LeafStop s) {
  switch (s) {
    case sampling::LeafStop::kNone:
      return "none";
    case sampling::LeafStop::kThreshold:
      return "threshold";
    case sampling::LeafStop::kMaxDepth:
      return "max_depth";
    case sampling::LeafStop::kUnsplittable:
      return "unsplittable";
    case sampling::LeafStop::kBudget:
      return "budget";
  }
  return "none";
}

sampling::LeafStop StopOf(const std::string& s) {
  for (auto v : {sampling::LeafStop::kNone, sampling::LeafStop::kThreshold, sampling::LeafStop::kMaxDepth,
                 sampling::LeafStop::kUnsplittable, sampling::LeafStop::kBudget})
    if (s == StopName(v)) return v;
  throw Corrupt("unknown leaf stop '" + s + "'");
}

}  // namespace fabatlas::artifact::format
