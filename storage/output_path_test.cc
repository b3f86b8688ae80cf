#include "storage/output_path.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <set>

#include "storage/processing_store.h"
#include "storage/run_store.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

namespace fs = std::filesystem;

RunInfo run_info(const std::string& name, std::int64_t started_ns) {
  RunInfo info;
  info.name = name;
  info.started_ns = started_ns;
  return info;
}

// A run as a logger and a processing leave it: the store, frames of two
// cameras (one in a folder of its own name), stored fields, a mask at the
// top of the run that the stored processing names.
class OutputPath : public ::testing::Test {
 protected:
  void SetUp() override {
    {
      auto store = RunStore::create(run(), run_info("guarded", 1'000), RunStore::CreateMode::kNew);
      store.add_frame({0, std::nullopt, 2'000, std::nullopt, "frames/cam0/f1.png", 8, 8, 8, true});
      store.add_frame({0, std::nullopt, 3'000, std::nullopt, "overhead/f2.png", 8, 8, 8, false});
      store.finish(RunStatus::kComplete, 4'000);
    }
    ProcessingStore(run(), true).begin_processing(R"({"mask": "holder-mask.png"})", 5'000);
    for (const char* folder : {"frames/cam0", "fields/p1", "masks", "overhead"}) fs::create_directories(run() / folder);
    for (const char* file : {"holder-mask.png", "process.lock"}) std::ofstream(run() / file) << "x";
  }
  fs::path run() const { return dir_ / "run"; }

  // What the check says of `path`, or "" when it allows it.
  static std::string refusal(const fs::path& path, std::string_view option = {}) {
    try {
      check_output_path(path, option);
    } catch (const OutputRefused& e) {
      return e.what();
    }
    return "";
  }

  testing::TempDir dir_;
};

TEST_F(OutputPath, EveryOwnFileOfARunIsRefused) {
  for (const char* name :
       {"run.sqlite", "run.sqlite-wal", "run.sqlite-shm", "run.sqlite-journal", "run.lock", "process.lock", "run.reserve"}) {
    const auto owned = run_owned_path(run() / name);
    ASSERT_TRUE(owned) << name;
    EXPECT_EQ(owned->run_dir, fs::weakly_canonical(run())) << name;
    EXPECT_NE(owned->what.find(name), std::string::npos) << owned->what;
  }
  EXPECT_NE(refusal(run() / "run.sqlite").find("its run store"), std::string::npos);
}

TEST_F(OutputPath, TheRunFolderAndEverythingInItsOwnFoldersIsRefused) {
  for (const fs::path relative : {"frames", "frames/cam0/f1.png", "frames/cam0/new.csv", "fields", "fields/p1/x.h5",
                                  "masks/m.png", "frames/no/such/folder/x.csv"}) {
    EXPECT_TRUE(run_owned_path(run() / relative)) << relative;
  }
  EXPECT_NE(refusal(run() / "frames/new.csv").find("inside its folder frames/"), std::string::npos);
  EXPECT_NE(refusal(run()).find("the run folder itself"), std::string::npos);
  EXPECT_NE(refusal(run().string() + "/").find("the run folder itself"), std::string::npos) << "a trailing slash";
}

TEST_F(OutputPath, FilesAndFoldersTheStoreNamesAreTheRunsToo) {
  EXPECT_NE(refusal(run() / "overhead/new.png").find("inside the folder overhead/, which its store names"),
            std::string::npos)
      << "a camera folder beside frames/";
  EXPECT_NE(refusal(run() / "holder-mask.png").find("the file holder-mask.png, which its store names"),
            std::string::npos)
      << "the stored processing's mask";
}

TEST_F(OutputPath, OtherSpellingsOfTheSameFileAreRefused) {
  const std::string message = refusal(run().string() + "/./run.sqlite");
  EXPECT_NE(message.find("its run store"), std::string::npos) << message;
  EXPECT_FALSE(refusal(run() / "frames/../run.sqlite").empty());
  EXPECT_FALSE(refusal(run() / "frames/cam0/../../fields/x.csv").empty());
  fs::create_symlink(run() / "run.sqlite", dir_ / "store-link");
  EXPECT_NE(refusal(dir_ / "store-link").find("its run store"), std::string::npos) << "a symlink to the store";
  fs::create_directory_symlink(run(), dir_ / "run-link");
  EXPECT_FALSE(refusal(dir_ / "run-link/run.sqlite-wal").empty()) << "through a symlink to the run folder";
  EXPECT_FALSE(refusal(dir_ / "run-link/frames/x.csv").empty());

  const fs::path before = fs::current_path();
  fs::current_path(run() / "frames");
  const std::string relative = refusal("../run.sqlite");
  fs::current_path(before);
  EXPECT_NE(relative.find("its run store"), std::string::npos) << "relative to the working folder: " << relative;
}

TEST_F(OutputPath, TheMessageNamesTheOptionThePathAndTheRun) {
  const fs::path given = run() / "run.sqlite";
  const std::string message = refusal(given, "--fields");
  EXPECT_NE(message.find("--fields '" + given.string() + "'"), std::string::npos) << message;
  EXPECT_NE(message.find("the run " + fs::weakly_canonical(run()).string() + " owns it"), std::string::npos) << message;
}

TEST_F(OutputPath, NewFilesAndFoldersBesideTheRunsOwnAreAllowed) {
  for (const fs::path relative : {"report.html", "report", "report/report.html", "fields.h5", "fields.xmf",
                                  "frames.csv", "run.sqlite.bak", "samples.csv", "nested-run/run.sqlite"}) {
    EXPECT_EQ(refusal(run() / relative), "") << relative;
  }
  EXPECT_EQ(refusal(dir_ / "elsewhere/out.csv"), "") << "a plain folder";
  EXPECT_EQ(refusal(dir_.path()), "") << "the folder that holds the run";
  EXPECT_EQ(refusal(dir_ / "run.sqlite"), "") << "a store name in a folder that holds no run";
}

TEST_F(OutputPath, ANestedRunIsGuardedAsWellAsTheRunAroundIt) {
  RunStore::create(run() / "inner", run_info("inner", 1'000), RunStore::CreateMode::kNew)
      .finish(RunStatus::kComplete, 2'000);
  const auto owned = run_owned_path(run() / "inner/run.sqlite");
  ASSERT_TRUE(owned);
  EXPECT_EQ(owned->run_dir, fs::weakly_canonical(run() / "inner"));
  EXPECT_EQ(refusal(run() / "inner/report.html"), "");
}

TEST_F(OutputPath, ANewRunFolderIsNeitherARunNorInsideOnesOwnFolders) {
  try {
    check_new_run_folder(run(), "--out");
    FAIL() << "a new run over an old one";
  } catch (const OutputRefused& e) {
    EXPECT_NE(std::string(e.what()).find("--out '" + run().string() + "': it already holds a run"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(check_new_run_folder(run() / "frames/replayed", "--out"), OutputRefused);
  EXPECT_NO_THROW(check_new_run_folder(dir_ / "replayed", "--out"));
  EXPECT_NO_THROW(check_new_run_folder(run() / "replayed", "--out")) << "a new folder beside the run's own";
}

TEST_F(OutputPath, CheckingAnOutputLeavesTheRunFolderAsItWas) {
  const auto entries = [&] {
    std::set<std::string> names;
    for (const auto& e : fs::recursive_directory_iterator(run())) names.insert(e.path().string());
    return names;
  };
  const auto before = entries();
  ASSERT_FALSE(before.count((run() / "run.sqlite-wal").string()));
  EXPECT_FALSE(refusal(run() / "overhead/x.png").empty()) << "the store was read";
  EXPECT_EQ(refusal(run() / "report.html"), "");
  EXPECT_EQ(entries(), before) << "no -wal or -shm left by reading the store";
}

TEST_F(OutputPath, ADamagedStoreStillHasItsFixedNames) {
  const fs::path broken = dir_ / "broken";
  fs::create_directories(broken);
  std::ofstream(broken / "run.sqlite") << "not a database";
  EXPECT_FALSE(refusal(broken / "run.sqlite").empty());
  EXPECT_FALSE(refusal(broken / "frames/x.png").empty());
  EXPECT_EQ(refusal(broken / "report.html"), "");
}

}  // namespace
}  // namespace bosfuse::storage
