// `bosfuse acquire` refuses a start it cannot go through with before it
// creates the run: exit 1, a message naming the key and line, and no run
// folder left behind (once, a 300-character camera name passed validation,
// failed with the system's "File name too long" and left an empty
// interrupted run).

#include <gtest/gtest.h>

#include <fstream>

#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

namespace fs = std::filesystem;

using testing::kBosfuse;

class AcquireStart : public ::testing::Test {
 protected:
  testing::CommandResult acquire(const std::string& experiment) {
    std::ofstream(dir_ / "exp.toml") << experiment;
    return testing::run_command(kBosfuse + " acquire " + (dir_ / "exp.toml").string() + " --out " + run_.string() +
                                " --duration 1s");
  }
  std::string camera(const std::string& name, const std::string& source) const {
    return "[run]\nname = \"start\"\n\n[[cameras]]\nname = \"" + name + "\"\n" + source;
  }

  testing::TempDir dir_;
  fs::path run_ = dir_ / "run";
};

TEST_F(AcquireStart, ACameraNameTooLongForAFolderLeavesNoRun) {
  fs::create_directories(dir_ / "shots");
  const auto result =
      acquire(camera(std::string(300, 'c'), "source = \"folder\"\nfolder = \"" + (dir_ / "shots").string() + "\"\n"));
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_NE(result.output.find("exp.toml:5: cameras[0].name: a camera name names its frame folder"), std::string::npos)
      << result.output;
  EXPECT_EQ(result.output.find("File name too long"), std::string::npos) << result.output;
  EXPECT_FALSE(fs::exists(run_)) << "a refused start left a run folder";
}

TEST_F(AcquireStart, AReplayCameraWithoutItsRecordedRunLeavesNoRun) {
  const auto result = acquire(
      camera("cam", "source = \"replay\"\nrun = \"" + (dir_ / "no-such-run").string() + "\"\ncamera = \"cam\"\n"));
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_NE(result.output.find("exp.toml:7: cameras[0].run: camera \"cam\": "), std::string::npos) << result.output;
  EXPECT_FALSE(fs::exists(run_)) << "a refused start left a run folder";
}

}  // namespace
}  // namespace bosfuse
