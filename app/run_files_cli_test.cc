// Nothing writes into a run by accident (issue 28, item 1): every output
// option of export, report, evaluate and replay aimed at one of a run's own
// files or folders — the store, its WAL, frames/, fields/, the run folder
// itself, in any spelling — is refused by the real executable with a
// message naming the path, a non-zero exit, and the run left as it was:
// the same store bytes, the same folder contents, `PRAGMA integrity_check`
// ok and `bosfuse runs` still reading it. A new file beside the run's own
// is written as asked.

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>

#include "report/test_readers.h"
#include "storage/database.h"
#include "tests/support/file_bytes.h"
#include "tests/support/subprocess.h"
#include "tests/support/synthetic_run.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

namespace fs = std::filesystem;
using report::testreaders::sh_quoted;

using testing::kBosfuse;

// Every file and folder under `dir`, with each file's size.
std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> entries;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const std::string name = e.path().lexically_relative(dir).string();
    entries.insert(e.is_regular_file() ? name + " " + std::to_string(e.file_size()) : name + "/");
  }
  return entries;
}

class RunFilesCli : public ::testing::Test {
 protected:
  void SetUp() override {
    testrun::create_run(run(), true);
    store_bytes_ = testing::file_bytes(run() / "run.sqlite");
    listing_ = listing(run());
  }
  fs::path run() const { return dir_ / "run"; }
  std::string q(const fs::path& path) const { return sh_quoted(path); }
  testing::CommandResult bosfuse(const std::string& args) { return testing::run_command(kBosfuse + " " + args, 120); }

  // `args` fails, says why naming `path`, and leaves the run as it was.
  void expect_refused(const std::string& args, const std::string& path) {
    SCOPED_TRACE(args);
    const auto result = bosfuse(args);
    EXPECT_NE(result.exit_code, 0) << result.output;
    EXPECT_NE(result.output.find("refusing to write"), std::string::npos) << result.output;
    EXPECT_NE(result.output.find("'" + path + "'"), std::string::npos) << "names the path: " << result.output;
    EXPECT_NE(result.output.find(fs::weakly_canonical(run()).string()), std::string::npos)
        << "names the run: " << result.output;
    expect_run_intact();
  }

  void expect_run_intact() {
    EXPECT_EQ(testing::file_bytes(run() / "run.sqlite"), store_bytes_) << "the store's bytes";
    EXPECT_EQ(listing(run()), listing_) << "nothing added, removed or resized in the run folder";
    storage::Database db((run() / "run.sqlite").string(), storage::Database::Mode::kReadOnly);
    auto check = db.prepare("PRAGMA integrity_check");
    ASSERT_TRUE(check.step());
    EXPECT_EQ(check.column_text(0), "ok");
    auto samples = db.prepare("SELECT count(*) FROM samples");
    ASSERT_TRUE(samples.step());
    EXPECT_EQ(samples.column_int64(0), 600);
    const auto runs = bosfuse("runs " + q(run()));
    EXPECT_EQ(runs.exit_code, 0) << runs.output;
    EXPECT_NE(runs.output.find("synthetic cooling"), std::string::npos) << runs.output;
    // These readers may leave SQLite's -wal and -shm beside the store: the next command is compared with that.
    store_bytes_ = testing::file_bytes(run() / "run.sqlite");
    listing_ = listing(run());
  }

  testing::TempDir dir_;
  std::string store_bytes_;
  std::set<std::string> listing_;
};

TEST_F(RunFilesCli, ExportOntoTheStoreOrItsCompanionsIsRefused) {
  const std::string store = (run() / "run.sqlite").string();
  expect_refused("export " + q(run()) + " --fields " + q(store), store);
  expect_refused("export " + q(run()) + " --csv -o " + q(store), store);
  const std::string wal = (run() / "run.sqlite-wal").string();
  expect_refused("export " + q(run()) + " --csv -o " + q(wal), wal);
  const std::string lock = (run() / "run.lock").string();
  expect_refused("export " + q(run()) + " --csv -o " + q(lock), lock);
}

TEST_F(RunFilesCli, OtherSpellingsOfTheStoreAreRefusedToo) {
  for (const std::string& path : {run().string() + "/./run.sqlite", run().string() + "/frames/../run.sqlite"}) {
    expect_refused("export " + q(run()) + " --csv -o " + q(path), path);
  }
  fs::create_symlink(run() / "run.sqlite", dir_ / "samples.csv");
  const std::string link = (dir_ / "samples.csv").string();
  expect_refused("export " + q(run()) + " --csv -o " + q(link), link);
  const auto relative = testing::run_command(
      "sh -c " + sh_quoted("cd " + q(run() / "frames") + " && " + kBosfuse + " export .. --csv -o ../run.sqlite"));
  EXPECT_NE(relative.exit_code, 0) << relative.output;
  EXPECT_NE(relative.output.find("'../run.sqlite'"), std::string::npos) << relative.output;
  expect_run_intact();
}

TEST_F(RunFilesCli, AReportIntoTheRunsOwnFoldersIsRefused) {
  for (const fs::path& out : {run() / "frames", run() / "fields", run() / "frames/report", run()}) {
    expect_refused("report " + q(run()) + " --out " + q(out), out.string());
  }
}

TEST_F(RunFilesCli, AnEvaluationIntoTheRunIsRefusedWithoutKnowingTheRun) {
  const std::string pair = "evaluate " + q(run() / "frames/reference.png") + " " + q(run() / "frames/frame0.png");
  const std::string store = (run() / "run.sqlite").string();
  expect_refused(pair + " -o " + q(store), store);
  const std::string in_frames = (run() / "frames/field.csv").string();
  expect_refused(pair + " -o " + q(in_frames), in_frames);
  const std::string map = (run() / "frames/map.png").string();
  expect_refused(pair + " -o " + q(dir_ / "field.csv") + " --map " + q(map), map);
  EXPECT_FALSE(fs::exists(dir_ / "field.csv")) << "refused before any work";
  const std::string h5 = (run() / "fields/seq.h5").string();
  expect_refused("evaluate --reference " + q(run() / "frames/reference.png") + " --sequence " + q(run() / "frames") +
                     " --out " + q(h5),
                 h5);
}

TEST_F(RunFilesCli, AReplayOntoItsOwnRecordIsRefusedWithTheSourceIntact) {
  expect_refused("replay " + q(run()) + " --out " + q(run()), run().string());
  const std::string frames = (run() / "frames").string();
  expect_refused("replay " + q(run()) + " --out " + q(frames), frames);
}

TEST_F(RunFilesCli, NewFilesBesideTheRunsOwnAreWrittenAsAsked) {
  const auto csv = bosfuse("export " + q(run()) + " --csv -o " + q(run() / "samples.csv"));
  ASSERT_EQ(csv.exit_code, 0) << csv.output;
  EXPECT_EQ(testing::file_bytes(run() / "samples.csv").rfind("time_utc", 0), 0u) << "the CSV's header";
  const auto report = bosfuse("report " + q(run()) + " --out " + q(run() / "report"));
  ASSERT_EQ(report.exit_code, 0) << report.output;
  EXPECT_TRUE(fs::is_regular_file(run() / "report/report.html"));
  for (const auto& entry : fs::directory_iterator(run() / "report")) {
    EXPECT_NE(entry.path().filename().string().front(), '.') << "a staging file left: " << entry.path();
  }
  EXPECT_EQ(testing::file_bytes(run() / "run.sqlite"), store_bytes_) << "the store is not written by an export or a report";
}

}  // namespace
}  // namespace bosfuse
