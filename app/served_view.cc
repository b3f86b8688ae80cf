#include "app/served_view.h"

#include <iostream>

#include "storage/storage_error.h"

namespace bosfuse::app {

ServedView::ServedView(const std::filesystem::path& run, const std::string& listen, bool require_token,
                       const std::string& address_option) {
  view::ViewOptions options;
  view::parse_listen_address(listen, options);
  options.require_token = require_token;
  options.address_option = address_option;
  try {
    server_.emplace(run, options);
  } catch (const storage::StorageError& e) {
    throw std::runtime_error("cannot view '" + run.string() + "': it is not a readable bosfuse run (" + e.what() + ")");
  }
  server_->listen();
  serving_ = std::thread([this] { server_->serve(); });
  if (!view::is_loopback_address(options.host)) {
    std::cerr << "warning: listening on " << options.host
              << ", not loopback: anyone who can reach this host and has the page's URL (its token) can read the "
                 "run, unencrypted\n";
  }
}

ServedView::~ServedView() {
  server_->stop();
  if (serving_.joinable()) serving_.join();
}

std::unique_ptr<ServedView> start_live_view(const std::filesystem::path& run, const std::string& listen) {
  if (listen.empty()) return nullptr;
  try {
    auto served = std::make_unique<ServedView>(run, listen, false, "--live HOST:PORT");
    std::cerr << "live view: " << served->url() << std::endl;
    return served;
  } catch (const std::exception& e) {
    std::cerr << "live view not started, recording goes on without it: " << e.what() << std::endl;
    return nullptr;
  }
}

void add_live_option(CLI::App& command, std::string& listen) {
  command
      .add_option_function<std::vector<std::string>>(
          "--live",
          [&listen](const std::vector<std::string>& values) {
            listen = values.empty() || values.front().empty() ? kDefaultListen : values.front();
          },
          std::string("Serve the live page of the run while recording, on HOST:PORT (") + kDefaultListen +
              " when not given); loopback unless you say otherwise")
      ->expected(0, 1)
      ->check(
          [](const std::string& value) {
            const auto colon = value.rfind(':');
            const std::string port = colon == std::string::npos ? "" : value.substr(colon + 1);
            const bool ok = value.empty() ||
                            (colon > 0 && !port.empty() && port.size() <= 5 &&
                             port.find_first_not_of("0123456789") == std::string::npos && std::stoi(port) <= 65535);
            return ok ? std::string()
                      : "--live takes HOST:PORT (e.g. " + std::string(kDefaultListen) + "), not '" + value +
                            "'; to serve on the default, put --live after the other arguments or write --live=" +
                            kDefaultListen;
          },
          "HOST:PORT");
}

}  // namespace bosfuse::app
