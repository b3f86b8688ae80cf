#include "sim/unique_fd.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/socket.h>

namespace bosfuse::sim {
namespace {

bool is_open(int fd) { return fcntl(fd, F_GETFD) != -1; }

TEST(UniqueFd, ClosesWhatItOwnsOnceAndHandsItOnWhenMoved) {
  int fds[2];
  ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, fds), 0);
  const int closed_by_destructor = fds[0];
  const int moved = fds[1];
  {
    UniqueFd a(closed_by_destructor);
    UniqueFd b(moved);
    UniqueFd c(std::move(b));
    EXPECT_FALSE(b);
    EXPECT_EQ(c.get(), moved);
    UniqueFd d;
    d = std::move(c);
    EXPECT_TRUE(is_open(moved));
    EXPECT_TRUE(is_open(closed_by_destructor));
  }
  EXPECT_FALSE(is_open(closed_by_destructor));
  EXPECT_FALSE(is_open(moved));
}

}  // namespace
}  // namespace bosfuse::sim
