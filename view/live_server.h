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
// It answers only requests that name it: the Host header must be
// `localhost`, `127.0.0.1`, `[::1]` or the address it listens on, with or
// without its port, or the request is 403 (a page of another site that a
// DNS-rebinding attack pointed at this port cannot read it). Off loopback
// (or when asked) every request must also carry a token, random per start,
// that the URL carries (`/?token=…`) and the page's cookie repeats. Each
// connection's request must arrive whole within 5 s of its first byte, and
// a client that acknowledges nothing of what is sent for 5 s is dropped
// (view/guarded_server.h): trickled requests and streams nobody reads do not
// hold the server's threads.
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
  // A token even on loopback (a machine others log into); off loopback always.
  bool require_token = false;
  // How the user gave the address, named when the port is in use.
  std::string address_option = "--listen HOST:PORT";
};

// 127.0.0.0/8, ::1 (also IPv4-mapped) and `localhost`: only this machine reaches it.
bool is_loopback_address(const std::string& host);

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
  // "http://HOST:PORT/", with "?token=…" when the server wants one.
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
