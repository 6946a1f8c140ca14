// The job store's tables and their numbered migrations (internal to
// storage/; the version is SQLite's user_version, job_store.h "Versions").
#pragma once

#include <string>

#include "fabatlas/sqlite/connection.h"

namespace fabatlas::storage::internal {

// Throws fabatlas::InputError "<path>: job store written by a newer
// fabatlas (schema version N; ...)" when the store's user_version is above
// kJobStoreSchemaVersion; reads only, so such a store is left untouched.
void CheckSchemaVersion(sqlite::Connection& db, const std::string& path);

// Brings the tables of any earlier store (or of none: a new file) to
// today's by the numbered migrations (schema.cc), then stamps
// kJobStoreSchemaVersion. Every migration is idempotent and all run on
// every open: the partial indexes came after version 1 was first stamped,
// and a coordinator from before them that opens the store adds its own
// indexes back. Throws through the connection's raise (ResourceError).
void MigrateSchema(sqlite::Connection& db);

}  // namespace fabatlas::storage::internal
