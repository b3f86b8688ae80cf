#include "storage/run_paths.h"

#include <gtest/gtest.h>

#include <fstream>

#include "storage/database.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

namespace fs = std::filesystem;
using namespace std::string_literals;

class RunPaths : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(run() / "frames/cam");
    std::ofstream(run() / "frames/cam/000001.png") << "png";
    std::ofstream(dir_ / "outside.png") << "secret";
  }
  fs::path run() const { return dir_ / "run"; }

  // The refusal's message, or "" when the path was accepted.
  std::string refusal(std::string_view stored) const {
    try {
      resolve_in_run(run(), stored);
      return "";
    } catch (const StorageError& e) {
      return e.what();
    }
  }

  testing::TempDir dir_;
};

TEST_F(RunPaths, PlainRelativePathsResolveInsideTheRun) {
  EXPECT_EQ(resolve_in_run(run(), "frames/cam/000001.png"), fs::canonical(run() / "frames/cam/000001.png"));
  EXPECT_EQ(resolve_in_run(run(), "./frames//cam/000001.png"), fs::canonical(run() / "frames/cam/000001.png"));
  // A file that does not exist (yet) is the caller's to report, not a refusal.
  EXPECT_EQ(resolve_in_run(run(), "fields/frame_2.csv"), fs::weakly_canonical(run()) / "fields/frame_2.csv");
}

TEST_F(RunPaths, EachRefusalSaysWhich) {
  EXPECT_EQ(refusal(""), "stored path '' refused: it is empty");
  EXPECT_EQ(refusal("/etc/passwd"), "stored path '/etc/passwd' refused: it is absolute");
  EXPECT_EQ(refusal("../outside.png"), "stored path '../outside.png' refused: it has a '..' component");
  EXPECT_EQ(refusal("frames/../../outside.png"),
            "stored path 'frames/../../outside.png' refused: it has a '..' component");
  EXPECT_EQ(refusal("frames/../frames/cam/000001.png"),
            "stored path 'frames/../frames/cam/000001.png' refused: it has a '..' component");
  EXPECT_EQ(refusal("frames/\x1b[2Jcam.png"),
            "stored path 'frames/\\x1B[2Jcam.png' refused: it holds a control character");
  EXPECT_EQ(refusal("frames/a\nb.png"), "stored path 'frames/a\\x0Ab.png' refused: it holds a control character");
  EXPECT_EQ(refusal("frames/cam\0/../../x"s), "stored path 'frames/cam\\x00/../../x' refused: it holds a control character");
}

TEST_F(RunPaths, ASymlinkOutOfTheRunIsRefused) {
  fs::create_symlink("/etc/passwd", run() / "frames/cam/000002.png");
  const std::string message = refusal("frames/cam/000002.png");
  EXPECT_EQ(message.rfind("stored path 'frames/cam/000002.png' refused: a symlink along it leads outside the run", 0),
            0u)
      << message;
  // A symlinked folder along the way counts too.
  fs::create_directory_symlink(dir_.path(), run() / "up");
  EXPECT_NE(refusal("up/outside.png"), "");
  // What counts is the file read: out of the run and back in names a run's file.
  EXPECT_EQ(refusal("up/run/frames/cam/000001.png"), "");
  // A relative symlink that climbs out.
  fs::create_symlink("../../../outside.png", run() / "frames/cam/000003.png");
  EXPECT_NE(refusal("frames/cam/000003.png"), "");
}

TEST_F(RunPaths, ASymlinkThatStaysInsideIsFine) {
  fs::create_symlink("000001.png", run() / "frames/cam/latest.png");
  fs::create_directory_symlink("frames/cam", run() / "cam");
  EXPECT_EQ(resolve_in_run(run(), "frames/cam/latest.png"), fs::canonical(run() / "frames/cam/000001.png"));
  EXPECT_EQ(resolve_in_run(run(), "cam/000001.png"), fs::canonical(run() / "frames/cam/000001.png"));
}

TEST_F(RunPaths, ARunFolderReachedThroughASymlinkStillWorks) {
  fs::create_directory_symlink(run(), dir_ / "alias");
  EXPECT_EQ(resolve_in_run(dir_ / "alias", "frames/cam/000001.png"), fs::canonical(run() / "frames/cam/000001.png"));
  // A sibling whose name starts with the run's is not inside it.
  fs::create_directories(dir_ / "run2");
  fs::create_directory_symlink(dir_ / "run2", run() / "next");
  EXPECT_NE(refusal("next/x.png"), "");
}

}  // namespace
}  // namespace bosfuse::storage
