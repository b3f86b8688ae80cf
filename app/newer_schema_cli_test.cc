// A run store written by a newer bosfuse is refused by every command that
// opens one, with the message `process` gives, and left exactly as it was:
// the real executable on a synthetic run whose schema_version row is bumped
// past the one this build knows.

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>

#include "storage/database.h"
#include "storage/schema.h"
#include "tests/support/browser.h"
#include "tests/support/file_bytes.h"
#include "tests/support/subprocess.h"
#include "tests/support/synthetic_run.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

namespace fs = std::filesystem;
using testing::shell_quote;

using testing::kBosfuse;

// Every file below `dir` with its bytes. SQLite's -shm index, and an empty
// -wal, are left out: SQLite makes both for any reader of a WAL database,
// and neither holds a record.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string name = fs::relative(entry.path(), dir).string();
    const bool index = name.ends_with("-shm") || (name.ends_with("-wal") && fs::file_size(entry.path()) == 0);
    if (entry.is_regular_file() && !index) files[name] = testing::file_bytes(entry.path());
  }
  return files;
}

// The files added, removed or changed between two snapshots.
std::string changes(const std::map<std::string, std::string>& before, const std::map<std::string, std::string>& after) {
  std::string names;
  for (const auto& [name, bytes] : after) {
    if (!before.contains(name) || before.at(name) != bytes) names += " " + name;
  }
  for (const auto& [name, bytes] : before) {
    if (!after.contains(name)) names += " -" + name;
  }
  return names;
}

class NewerSchemaCli : public ::testing::Test {
 protected:
  void SetUp() override {
    testrun::Truth truth;
    truth.config_toml = kExperiment;
    testrun::create_run(run_, true, truth);
    storage::Database db((run_ / "run.sqlite").string(), storage::Database::Mode::kReadWrite);
    db.execute("INSERT INTO schema_version (version, applied_ns) VALUES (" +
               std::to_string(storage::kSchemaVersion + 1) + ", 0)");
  }

  static constexpr const char* kExperiment =
      "[[devices]]\nname = \"adam\"\nprofile = \"adam-6018\"\nhost = \"127.0.0.1\"\nport = 1\n"
      "[[devices.channels]]\nname = \"tc0\"\ninput = 0\n";
  testing::TempDir dir_;
  fs::path run_ = dir_ / "runs" / "newer";
};

TEST_F(NewerSchemaCli, EveryCommandThatOpensTheStoreRefusesItAndChangesNothing) {
  std::ofstream(dir_ / "exp.toml") << kExperiment;
  const std::string run = shell_quote(run_);
  const std::string out = (dir_ / "out").string();
  const std::vector<std::string> commands = {
      "runs " + run,
      "runs " + shell_quote(dir_ / "runs"),
      "export " + run + " --csv -o " + shell_quote(out + ".csv"),
      "export " + run + " --fields " + shell_quote(out + ".h5"),
      "report " + run + " -o " + shell_quote(out + "-report"),
      "view " + run + " --listen 127.0.0.1:0",
      "replay " + run + " -o " + shell_quote(out + "-replay"),
      "mark " + run + " 'heater off'",
      "calibrate " + run,
      "process " + run,
      "process " + run + " --resume",
      "acquire " + shell_quote(dir_ / "exp.toml") + " --append -o " + run + " --duration 1s",
  };
  const std::string refusal = "has schema version " + std::to_string(storage::kSchemaVersion + 1) +
                              ", newer than this bosfuse understands (" + std::to_string(storage::kSchemaVersion) + ")";
  const auto before = snapshot(run_);
  ASSERT_TRUE(before.contains("run.sqlite"));
  for (const std::string& command : commands) {
    SCOPED_TRACE(command);
    const auto result = testing::run_command(kBosfuse + " " + command, 20);
    EXPECT_EQ(result.exit_code, 1) << result.output;
    EXPECT_NE(result.output.find(refusal), std::string::npos) << result.output;
    EXPECT_EQ(changes(before, snapshot(run_)), "") << "the refused run changed";
  }
  // A listing names the refused run and still lists the others.
  testrun::create_run(dir_ / "runs" / "readable", false);
  const auto listing = testing::run_command(kBosfuse + " runs " + shell_quote(dir_ / "runs"), 20);
  EXPECT_EQ(listing.exit_code, 1) << listing.output;
  EXPECT_NE(listing.output.find("readable "), std::string::npos) << listing.output;
  EXPECT_NE(listing.output.find("1 of 2 runs could not be read: newer"), std::string::npos) << listing.output;
  for (const char* written : {".csv", ".h5", "-report", "-replay"}) {
    EXPECT_FALSE(fs::exists(out + written)) << out + written << " was written from a store that was refused";
  }
}

}  // namespace
}  // namespace bosfuse
