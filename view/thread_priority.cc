#include "view/thread_priority.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace bosfuse::view {
namespace {

constexpr int kViewerNiceness = 10;

}  // namespace

void yield_to_the_logger() {
  thread_local bool lowered = false;
  if (lowered) return;
  lowered = true;
  const auto thread_id = static_cast<id_t>(::syscall(SYS_gettid));
  ::setpriority(PRIO_PROCESS, thread_id, kViewerNiceness);
}

}  // namespace bosfuse::view
