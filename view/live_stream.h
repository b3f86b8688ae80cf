#pragma once
// LiveStream is one client's Server-Sent Events stream over a run (format
// in docs/VIEW.md): the run's clock and status, then every event, sample
// and frame count committed after the client's cursor, in commit order per
// table. Every record message carries `id:` = the cursor after it, so a
// client that reconnects with Last-Event-ID continues with nothing lost and
// nothing repeated. Times are experiment seconds (t_s) of the run's clock;
// when the clock changes (its origin marker was recorded, say) a new
// `clock` message says so before any record timed by it.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "view/live_bos.h"
#include "view/run_watch.h"

namespace bosfuse::view {

// A cursor as the stream's event id, "S-E-F" (sample rowid, event id, frame
// id), e.g. "1200-3-17"; parse_cursor() reads it back and returns nothing
// for anything else (a client's Last-Event-ID header is input like any other).
std::string format_cursor(const TailCursor& cursor);
std::optional<TailCursor> parse_cursor(const std::string& text);

// One SSE message; `data` must be one line (compact JSON is).
std::string sse_message(std::string_view type, std::string_view id, std::string_view data);

class LiveStream {
 public:
  // Rows read per call of next(), per table: bounds each write to a client.
  static constexpr int kRowsPerRead = 2000;

  // `bos`, when given, adds the live BOS results (`bos` and `bos-state`
  // messages, without ids: the whole series is sent on every connection).
  LiveStream(const std::filesystem::path& run_dir, TailCursor from, const LiveBos* bos = nullptr);

  // The next part of the stream, given the run as `snapshot` sees it; empty
  // when the client has everything the run committed.
  std::string next(const RunSnapshot& snapshot);
  const TailCursor& cursor() const { return cursor_; }

 private:
  std::string clock_and_status(const RunSnapshot& snapshot);
  std::string live_bos(const storage::ExperimentClock& clock);

  RunTail tail_;
  TailCursor cursor_;
  std::string sent_clock_;
  std::string sent_status_;
  const LiveBos* bos_;
  std::size_t bos_sent_ = 0;
  std::string sent_bos_state_;
  std::optional<std::int64_t> first_frame_t_ns_;
};

}  // namespace bosfuse::view
