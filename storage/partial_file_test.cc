#include "storage/partial_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <set>
#include <sstream>

#include "storage/output_path.h"
#include "storage/run_store.h"
#include "tests/support/file_bytes.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

namespace fs = std::filesystem;

RunInfo guarded_run_info(const std::string& name, std::int64_t started_ns) {
  RunInfo info;
  info.name = name;
  info.started_ns = started_ns;
  return info;
}

std::set<std::string> names_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.insert(entry.path().filename().string());
  return names;
}

TEST(PartialFile, ItsTemporaryIsAHiddenFileBesideTheDestinationWithItsExtension) {
  testing::TempDir dir;
  const PartialFile a(dir / "fields.h5"), b(dir / "fields.h5");
  EXPECT_EQ(a.path().parent_path(), dir.path());
  EXPECT_EQ(a.path().extension(), ".h5") << "writers that choose their format by the name still can";
  EXPECT_EQ(a.path().filename().string().front(), '.');
  EXPECT_NE(a.path(), b.path()) << "two outputs of one process never share a temporary";
}

TEST(PartialFileStream, CloseReplacesTheDestinationAndLeavesNothingElse) {
  testing::TempDir dir;
  std::ofstream(dir / "out.csv") << "old\n";
  PartialFileStream out(dir / "out.csv");
  out.stream() << "new\n";
  EXPECT_EQ(testing::file_bytes(dir / "out.csv"), "old\n") << "the destination is untouched until close()";
  out.close();
  EXPECT_EQ(testing::file_bytes(dir / "out.csv"), "new\n");
  EXPECT_EQ(names_in(dir.path()), std::set<std::string>{"out.csv"});
}

TEST(PartialFileStream, AnExceptionBeforeCloseLeavesTheOldFileByteIdenticalAndNoTemporary) {
  testing::TempDir dir;
  const std::string old_bytes("old\0bytes\xff\n", 11);
  std::ofstream(dir / "out.csv", std::ios::binary) << old_bytes;
  try {
    PartialFileStream out(dir / "out.csv");
    out.stream() << std::string(100'000, 'x');  // past any buffer: really on disk
    throw std::runtime_error("the export failed half-way");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(testing::file_bytes(dir / "out.csv"), old_bytes);
  EXPECT_EQ(names_in(dir.path()), std::set<std::string>{"out.csv"});
}

TEST(PartialFile, AWriterThatOpensItsOwnFileWritesTheTemporary) {
  testing::TempDir dir;
  {
    PartialFile file(dir / "map.png");
    std::ofstream(file.path()) << "drawn";
    EXPECT_FALSE(fs::exists(dir / "map.png"));
  }
  EXPECT_TRUE(fs::is_empty(dir.path())) << "an uncommitted temporary is removed";
  PartialFile file(dir / "map.png");
  std::ofstream(file.path()) << "drawn";
  file.commit();
  EXPECT_EQ(testing::file_bytes(dir / "map.png"), "drawn");
}

TEST(PartialFile, ASymlinkedDestinationIsWrittenThroughAndStaysALink) {
  testing::TempDir dir;
  fs::create_directory(dir / "real");
  std::ofstream(dir / "real/out.csv") << "old";
  fs::create_symlink(dir / "real/out.csv", dir / "link.csv");
  PartialFileStream out(dir / "link.csv");
  out.stream() << "new";
  out.close();
  EXPECT_TRUE(fs::is_symlink(dir / "link.csv"));
  EXPECT_EQ(testing::file_bytes(dir / "real/out.csv"), "new");
}

TEST(PartialFile, ADestinationThatIsNoRegularFileIsWrittenDirectly) {
  testing::TempDir dir;
  ASSERT_EQ(mkfifo((dir / "pipe").c_str(), 0600), 0);
  PartialFile file(dir / "pipe");
  EXPECT_EQ(file.path(), dir / "pipe") << "renaming onto a pipe or a device would replace it";
  file.commit();
  EXPECT_TRUE(fs::is_fifo(dir / "pipe"));
}

TEST(PartialFile, ARunsOwnFileIsRefusedBeforeAnythingIsWritten) {
  testing::TempDir dir;
  RunStore::create(dir / "run", guarded_run_info("guarded", 1), RunStore::CreateMode::kNew).finish(RunStatus::kComplete, 2);
  const std::string before = testing::file_bytes(dir / "run/run.sqlite");
  const auto entries = names_in(dir / "run");
  EXPECT_THROW(PartialFileStream(dir / "run/run.sqlite"), OutputRefused);
  EXPECT_THROW(PartialFile(dir / "run/frames/x.png"), OutputRefused);
  EXPECT_THROW(PartialFolder(dir / "run/fields"), OutputRefused);
  EXPECT_EQ(testing::file_bytes(dir / "run/run.sqlite"), before);
  EXPECT_EQ(names_in(dir / "run"), entries) << "no temporary, no folder made";
}

TEST(PartialFolder, ItsFilesReplaceTheDestinationsOnlyAtTheCommit) {
  testing::TempDir dir;
  fs::create_directory(dir / "report");
  std::ofstream(dir / "report/report.html") << "old report";
  std::ofstream(dir / "report/notes.txt") << "the user's";
  {
    PartialFolder folder(dir / "report");
    std::ofstream(folder.path() / "report.html") << "new report";
    std::ofstream(folder.path() / "fig.png") << "png";
    EXPECT_EQ(testing::file_bytes(dir / "report/report.html"), "old report");
    const auto moved = folder.commit();
    EXPECT_EQ(moved.size(), 2u);
  }
  EXPECT_EQ(testing::file_bytes(dir / "report/report.html"), "new report");
  EXPECT_EQ(testing::file_bytes(dir / "report/fig.png"), "png");
  EXPECT_EQ(names_in(dir / "report"), (std::set<std::string>{"fig.png", "notes.txt", "report.html"}))
      << "no staging folder left, the user's own file kept";
}

TEST(PartialFolder, WithoutACommitTheOldFilesStayAndNothingIsLeft) {
  testing::TempDir dir;
  fs::create_directory(dir / "report");
  std::ofstream(dir / "report/report.html") << "old report";
  {
    PartialFolder folder(dir / "report");
    std::ofstream(folder.path() / "report.html") << "half a report";
  }
  EXPECT_EQ(testing::file_bytes(dir / "report/report.html"), "old report");
  EXPECT_EQ(names_in(dir / "report"), std::set<std::string>{"report.html"});
  { PartialFolder folder(dir / "new/report"); }
  EXPECT_FALSE(fs::exists(dir / "new/report")) << "a folder it made and never filled is removed";
}

}  // namespace
}  // namespace bosfuse::storage
