#include "app/run_argument.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/support/temp_dir.h"

namespace bosfuse::app {
namespace {

namespace fs = std::filesystem;

TEST(RunArgument, AMissingPathIsNoSuchFolder) {
  testing::TempDir dir;
  std::string path = (dir.path() / "nothing-here").string();
  EXPECT_EQ(resolve_run_argument(path), "no such folder: '" + path + "'");
}

TEST(RunArgument, AFileInsideARunFolderNamesTheRun) {
  testing::TempDir dir;
  fs::create_directories(dir.path() / "run");
  std::ofstream(dir.path() / "run" / "run.sqlite") << "";
  std::string path = (dir.path() / "run" / "run.sqlite").string();
  EXPECT_EQ(resolve_run_argument(path), "");
  EXPECT_EQ(fs::path(path), dir.path() / "run");
}

TEST(RunArgument, AFileOutsideARunIsRefusedByName) {
  testing::TempDir dir;
  std::ofstream(dir.path() / "notes.txt") << "x";
  std::string path = (dir.path() / "notes.txt").string();
  EXPECT_NE(resolve_run_argument(path).find("is a file, not a run folder"), std::string::npos);
  EXPECT_EQ(fs::path(path), dir.path() / "notes.txt") << "a refused argument is left as given";
}

TEST(RunArgument, AFolderIsLeftForTheStoreToJudge) {
  testing::TempDir dir;
  std::string path = dir.path().string();
  EXPECT_EQ(resolve_run_argument(path), "");
  EXPECT_EQ(path, dir.path().string());
}

}  // namespace
}  // namespace bosfuse::app
