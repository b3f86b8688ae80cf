// main() of the umockdev tests: the testbed only works when the process runs
// with umockdev's preload library, so a binary started without it (by ctest,
// a debugger, or by hand) starts itself again under umockdev-wrapper.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string_view>
#include <vector>

namespace {

bool preload_active() {
  const char* preload = std::getenv("LD_PRELOAD");
  return preload && std::string_view(preload).find("libumockdev-preload") != std::string_view::npos;
}

}  // namespace

int main(int argc, char** argv) {
  if (!preload_active()) {
    std::vector<char*> args = {const_cast<char*>(UMOCKDEV_WRAPPER)};
    args.insert(args.end(), argv, argv + argc);
    args.push_back(nullptr);
    execv(UMOCKDEV_WRAPPER, args.data());
    std::perror("cannot start " UMOCKDEV_WRAPPER);
    return 1;
  }
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
