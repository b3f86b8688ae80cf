#pragma once
// The live page (view/live_server.h) served on a thread of its own, as
// `bosfuse view` runs it and as the recording commands start it inside the
// logger with `--live [HOST:PORT]`: bound before the constructor returns
// (so a port in use is said at once), a warning on stderr when it is not on
// loopback (where the page wants the token its URL carries), stopped with
// the object.

#include <CLI/CLI.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "view/live_server.h"

namespace bosfuse::app {

inline constexpr const char* kDefaultListen = "127.0.0.1:8080";

class ServedView {
 public:
  // Throws std::runtime_error with a message for the user: a folder that is
  // no readable run, a bad address, a port in use. `require_token`: the
  // URL's token also on loopback (off loopback it is always wanted).
  // address_option: how the user gave the address, named when the port is in use.
  ServedView(const std::filesystem::path& run, const std::string& listen, bool require_token = false,
             const std::string& address_option = "--listen HOST:PORT");
  ~ServedView();
  ServedView(const ServedView&) = delete;
  ServedView& operator=(const ServedView&) = delete;

  // With the token when the page wants one: the only way in, so say it whole.
  std::string url() const { return server_->url(); }

 private:
  std::optional<view::LiveServer> server_;
  std::thread serving_;
};

// The live page of a recording command, when `listen` is not empty: its URL
// said on stderr, or, when it cannot start (a port in use, say), why — the
// recording goes on without it, since the run matters more than its page.
std::unique_ptr<ServedView> start_live_view(const std::filesystem::path& run, const std::string& listen);

// `--live [HOST:PORT]` on a recording command: `listen` stays empty unless
// it is given, and is kDefaultListen when given without an address.
void add_live_option(CLI::App& command, std::string& listen);

}  // namespace bosfuse::app
