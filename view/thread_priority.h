#pragma once
// The viewer's threads give way to the logger's: inside `acquire --live`
// (and beside it on a 2-core machine) a poll that is due must not wait for
// a page being served. Every thread of the viewer — its poller, the live
// BOS evaluation, the HTTP handlers and the accept loop — lowers its own
// scheduling priority once (nice 10; on Linux niceness is per thread).

namespace bosfuse::view {

// Idempotent per thread; a failure (no permission to change it) is ignored:
// the viewer then runs at the logger's priority, as it did before.
void yield_to_the_logger();

}  // namespace bosfuse::view
