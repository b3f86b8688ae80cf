#pragma once
// The run store's schema and its forward migrations. A run store records
// its schema version in `schema_version`; opening a store applies, in order
// and each in its own transaction, every migration newer than that version.
// A store written by a newer bosfuse is refused rather than misread. The
// schema is documented for users in docs/SCHEMA.md.

#include <array>
#include <span>
#include <string_view>

#include "storage/database.h"

namespace bosfuse::storage {

struct Migration {
  int version;           // the schema version this migration produces
  std::string_view sql;  // statements run in one transaction
};

// The migrations of this bosfuse build, oldest first.
std::span<const Migration> schema_migrations();

inline constexpr int kSchemaVersion = 7;

// The uncertainty columns of a probe sample (version 5), in probe_samples and
// staged_probe_samples alike, in the order ProcessingStore writes them.
inline constexpr std::array<std::string_view, 5> kProbeSampleSigmaColumns = {
    "sigma_u_px", "sigma_v_px", "sigma_shift_px", "sigma_random_c", "sigma_systematic_c"};

// 0 for a file with no schema yet.
int schema_version(Database& db);

// Throws StorageError when `db` was written by a newer bosfuse (a schema
// version above `newest`). Every opening of a run store, for reading as
// much as for writing, goes through it (RunStore, ProcessingStore,
// RunTail): a newer schema may have changed what a column means, so no
// command reads such a store, and the refusal changes nothing in it.
void require_known_schema(Database& db, int newest = kSchemaVersion);

// Brings the database to the newest version in `migrations` (default: this
// build's). Returns the version it started from.
int migrate(Database& db, std::span<const Migration> migrations = schema_migrations());

}  // namespace bosfuse::storage
