#include "app/output_stream.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>

#include "tests/support/file_bytes.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::app {
namespace {

// Standard output into a string for the test's lifetime.
class CapturedStdout {
 public:
  CapturedStdout() : previous_(std::cout.rdbuf(text_.rdbuf())) {}
  ~CapturedStdout() { std::cout.rdbuf(previous_); }
  std::string text() const { return text_.str(); }

 private:
  std::ostringstream text_;
  std::streambuf* previous_;
};

TEST(OutputStream, ADashIsStandardOutput) {
  CapturedStdout captured;
  OutputStream out("-");
  EXPECT_TRUE(out.to_standard_output());
  out.stream() << "a,b\n1,2\n";
  out.close();
  EXPECT_EQ(captured.text(), "a,b\n1,2\n");
}

TEST(OutputStream, AnyOtherNameIsAFile) {
  testing::TempDir dir;
  CapturedStdout captured;
  OutputStream out((dir / "x.csv").string());
  EXPECT_FALSE(out.to_standard_output());
  out.stream() << "data\n";
  out.close();
  EXPECT_EQ(testing::file_bytes(dir / "x.csv"), "data\n");
  EXPECT_EQ(captured.text(), "") << "nothing on standard output when the data went to a file";
}

TEST(OutputStream, AFileThatCannotBeCreatedFailsBeforeAnyWork) {
  testing::TempDir dir;
  const std::string path = (dir / "no-such-folder" / "x.csv").string();
  try {
    OutputStream out(path);
    FAIL() << "opened " << path;
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot write '" + path + "'");
  }
}

TEST(OutputStream, AFailedWriteIsAnErrorNotAShortFile) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  OutputStream out("/dev/full");
  out.stream() << "data that does not fit\n";
  EXPECT_THROW(
      {
        try {
          out.close();
        } catch (const std::runtime_error& e) {
          EXPECT_EQ(std::string(e.what()), "could not write '/dev/full'");
          throw;
        }
      },
      std::runtime_error);
}

TEST(OutputStream, OptionsNeedingAFileRefuseADashWithTheReason) {
  EXPECT_NO_THROW(refuse_standard_output("map.png", "--map", "a PNG image"));
  try {
    refuse_standard_output("-", "--map", "the image format comes from its name");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "--map cannot be standard output ('-'): the image format comes from its name");
  }
}

TEST(OutputStream, ACommandThatFailsBeforeCloseLeavesTheOldFileWhole) {
  testing::TempDir dir;
  std::ofstream(dir / "fit.json") << "{\"k\": 0.01}\n";
  try {
    OutputStream out((dir / "fit.json").string());
    out.stream() << "{\"k\": ";
    throw std::runtime_error("the fit failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(testing::file_bytes(dir / "fit.json"), "{\"k\": 0.01}\n");
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) files += entry.exists();
  EXPECT_EQ(files, 1u) << "no temporary left beside it";
}

TEST(OutputStream, ARunsOwnFileIsRefusedNamingTheOption) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "run");
  std::ofstream(dir / "run/run.sqlite") << "a store";
  const std::string store = (dir / "run/run.sqlite").string();
  try {
    OutputStream out(store, "--json");
    FAIL() << "opened " << store;
  } catch (const storage::OutputRefused& e) {
    EXPECT_EQ(std::string(e.what()).rfind("refusing to write --json '" + store + "'", 0), 0u) << e.what();
  }
  EXPECT_EQ(testing::file_bytes(dir / "run/run.sqlite"), "a store");
  EXPECT_NO_THROW(check_output("-", "--json")) << "standard output is no run's file";
  EXPECT_NO_THROW(check_output("", "--json")) << "an option not given";
  EXPECT_THROW(check_figure_output((dir / "run/frames/map.png").string(), "--map"), storage::OutputRefused);
}

TEST(OutputStream, TheTextResultMovesToStandardErrorWhenTheDataTookStandardOutput) {
  EXPECT_EQ(&text_stream(false), &std::cout);
  const auto level = spdlog::get_level();
  spdlog::set_level(spdlog::level::info);
  EXPECT_EQ(&text_stream(true), &std::cerr);
  spdlog::set_level(spdlog::level::warn);  // --quiet
  std::ostream& quiet = text_stream(true);
  EXPECT_NE(&quiet, &std::cerr);
  EXPECT_NE(&quiet, &std::cout);
  quiet << "dropped\n";
  EXPECT_EQ(&text_stream(false), &std::cout) << "--quiet keeps the result when it is the output";
  spdlog::set_level(level);
}

}  // namespace
}  // namespace bosfuse::app
