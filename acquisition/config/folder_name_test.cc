#include "acquisition/config/folder_name.h"

#include <gtest/gtest.h>

namespace bosfuse::acquisition {
namespace {

TEST(FolderName, PortableNamesUpToTheLimitPass) {
  EXPECT_EQ(folder_name_problem("cam-0_B"), "");
  EXPECT_EQ(folder_name_problem(std::string(kMaxFolderNameBytes, 'c')), "");
}

TEST(FolderName, LongEmptyAndUnportableNamesAreRefused) {
  EXPECT_NE(folder_name_problem(std::string(kMaxFolderNameBytes + 1, 'c')).find("more than the 64"), std::string::npos);
  EXPECT_NE(folder_name_problem(std::string(300, 'c')).find("300 bytes long"), std::string::npos);
  EXPECT_NE(folder_name_problem(""), "");
  for (const char* name : {"my cam", "a/b", "..", ".hidden", "cam.1", "caf\xc3\xa9", "a\\b", "a:b"}) {
    EXPECT_NE(folder_name_problem(name), "") << name;
  }
}

}  // namespace
}  // namespace bosfuse::acquisition
