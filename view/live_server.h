#pragma once
// LiveServer is `bosfuse view`: an HTTP server over one run folder, live
// while another process records into it and equally over a finished run.
// It is read-only, binds to loopback unless told otherwise, and serves only
// its own routes — anything else is 404 and reads nothing:
//
//   /           the page (view/page.h)
//   /chart.js   Debian's Chart.js, read once at start
//   /api/run    the run's name, status, time basis, channels and devices (JSON)
//   /frame.png  the newest live-evaluated frame, downscaled (view/live_bos.h)
//   /events     the records and live BOS results as Server-Sent Events (view/live_stream.h)
//
// Use: construct (throws ViewError or storage::StorageError with a message
// for the user), listen(), then serve() on a thread of its own until stop().

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

namespace bosfuse::view {

class ViewError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ViewOptions {
  std::string host = "127.0.0.1";
  int port = 8080;  // 0: any free port
  std::chrono::milliseconds poll_period{100};
  int max_clients = 16;  // open /events streams; one more is refused with 503
  std::filesystem::path chartjs_path;  // empty: Debian's libjs-chart.js
};

// "127.0.0.1:8080", "[::1]:8080" or ":8080" (loopback) into host and port;
// throws ViewError naming the text otherwise.
void parse_listen_address(const std::string& text, ViewOptions& options);

class LiveServer {
 public:
  LiveServer(const std::filesystem::path& run_dir, ViewOptions options);
  ~LiveServer();
  LiveServer(const LiveServer&) = delete;
  LiveServer& operator=(const LiveServer&) = delete;

  // Binds the address; returns the port (the chosen one for port 0).
  // Throws ViewError saying whether the port is in use.
  int listen();
  std::string url() const;
  // Answers requests until stop(); call after listen().
  void serve();
  // Ends serve() and every open stream within about a poll period. Any thread.
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace bosfuse::view
