#include "view/live_server.h"

#include <httplib.h>

#include <nlohmann/json.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/random.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "view/guarded_server.h"
#include "view/live_bos.h"
#include "view/live_stream.h"
#include "view/page.h"
#include "view/run_watch.h"
#include "view/thread_priority.h"

namespace bosfuse::view {
namespace {

// A silent stream says something this often, so a client that went away is
// noticed (the write fails) and its slot freed.
constexpr auto kKeepAlivePeriod = std::chrono::seconds(5);
// Handler threads beyond the streams: the page, chart.js and /api/run stay
// answerable while every stream slot is taken and a few dozen more
// connections dribble their requests in (each holds a thread until
// kConnectionLimits cuts it off).
constexpr int kSpareThreads = 28;
// docs/VIEW.md, "Security stance": 5 s to begin a request, 5 s to send it
// whole, 5 s for a client to acknowledge something of what it is sent.
const ConnectionLimits kConnectionLimits{};
// No route takes a body.
constexpr std::size_t kMaxRequestBody = 64 * 1024;
// Reads of a stream that fail in a row before the page is told the run cannot be read.
constexpr int kFailuresBeforeError = 3;

// httplib's pool whose threads give way to the logger (thread_priority.h).
class YieldingThreadPool : public httplib::ThreadPool {
 public:
  using httplib::ThreadPool::ThreadPool;
  void enqueue(std::function<void()> task) override {
    httplib::ThreadPool::enqueue([task = std::move(task)] {
      yield_to_the_logger();
      task();
    });
  }
};

std::string read_chartjs(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in || text.str().empty()) {
    throw ViewError("cannot read Chart.js from " + path.string() +
                    "; the page needs it (install Debian's libjs-chart.js)");
  }
  return text.str();
}

std::string unreadable_run_message(const std::exception& e) {
  return std::string("the run cannot be read now (") + e.what() +
         "); if this persists its database is damaged — the viewer keeps trying";
}

std::string lowercase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// 0.0.0.0 or ::, where the name a client uses for this host is not known in advance.
bool is_wildcard_address(const std::string& host) {
  in6_addr v6{};
  in_addr v4{};
  if (inet_pton(AF_INET, host.c_str(), &v4) == 1) return v4.s_addr == htonl(INADDR_ANY);
  return inet_pton(AF_INET6, host.c_str(), &v6) == 1 && IN6_IS_ADDR_UNSPECIFIED(&v6);
}

// 128 bits from the kernel's random source, as hex.
std::string random_token() {
  unsigned char bytes[16];
  if (getrandom(bytes, sizeof bytes, 0) != static_cast<ssize_t>(sizeof bytes)) {
    throw ViewError(std::string("cannot draw the page's token from the kernel: ") + std::strerror(errno));
  }
  static constexpr char kHex[] = "0123456789abcdef";
  std::string token;
  for (const unsigned char b : bytes) token += {kHex[b >> 4], kHex[b & 15]};
  return token;
}

// Compares in time independent of where they differ, so the token is not
// guessed a character at a time by timing.
bool same_secret(const std::string& given, const std::string& secret) {
  if (given.size() != secret.size()) return false;
  unsigned char difference = 0;
  for (std::size_t i = 0; i < secret.size(); ++i) difference |= given[i] ^ secret[i];
  return difference == 0;
}

// The value of cookie `name` in the request's Cookie headers, or empty.
std::string cookie_value(const httplib::Request& request, const std::string& name) {
  const auto [first, last] = request.headers.equal_range("Cookie");
  for (auto header = first; header != last; ++header) {
    std::istringstream pairs(header->second);
    for (std::string pair; std::getline(pairs, pair, ';');) {
      const auto start = pair.find_first_not_of(' ');
      if (start != std::string::npos && pair.compare(start, name.size() + 1, name + "=") == 0) {
        return pair.substr(start + name.size() + 1);
      }
    }
  }
  return {};
}

void refuse(httplib::Response& response, const std::string& why) {
  response.status = 403;
  response.set_content(why + "\n", "text/plain");
}

}  // namespace

bool is_loopback_address(const std::string& host) {
  if (lowercase(host) == "localhost") return true;
  in_addr v4{};
  if (inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  if (inet_pton(AF_INET6, host.c_str(), &v6) != 1) return false;
  return IN6_IS_ADDR_LOOPBACK(&v6) || (IN6_IS_ADDR_V4MAPPED(&v6) && v6.s6_addr[12] == 127);
}

void parse_listen_address(const std::string& text, ViewOptions& options) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos) throw ViewError("--listen wants HOST:PORT, e.g. 127.0.0.1:8080, not '" + text + "'");
  std::string host = text.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  int port = -1;
  const std::string port_text = text.substr(colon + 1);
  const auto [end, ec] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (ec != std::errc() || end != port_text.data() + port_text.size() || port < 0 || port > 65535) {
    throw ViewError("--listen: '" + port_text + "' is not a port (0..65535)");
  }
  options.host = host.empty() ? "127.0.0.1" : host;
  options.port = port;
}

struct LiveServer::Impl {
  Impl(const std::filesystem::path& run_dir, ViewOptions opts)
      : options(std::move(opts)),
        chartjs(read_chartjs(options.chartjs_path.empty() ? std::filesystem::path(BOSFUSE_CHARTJS_PATH)
                                                          : options.chartjs_path)),
        watch(run_dir, options.poll_period),
        bos(watch),
        server(kConnectionLimits),
        token(options.require_token || !is_loopback_address(options.host) ? random_token() : "") {
    const std::size_t threads = static_cast<std::size_t>(options.max_clients + kSpareThreads);
    server.new_task_queue = [threads] { return new YieldingThreadPool(threads); };
    // httplib's default adds SO_REUSEPORT, with which a second viewer on the
    // same port would bind too and take half the requests; SO_REUSEADDR alone
    // still allows a restart while old connections linger in TIME_WAIT.
    server.set_socket_options([](socket_t sock) {
      int yes = 1;
      setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    server.set_payload_max_length(kMaxRequestBody);
    route();
  }

  // One client's stream and what the server keeps about it.
  struct StreamState {
    StreamState(const std::filesystem::path& run_dir, TailCursor from, const LiveBos* bos)
        : stream(run_dir, from, bos) {}
    LiveStream stream;
    std::chrono::steady_clock::time_point last_write = std::chrono::steady_clock::now();
    bool opening = true;
    int failures = 0;  // reads that failed in a row
    bool error_sent = false;
  };

  void route();
  void admit_hosts_for(int listening_port);
  bool admit(const httplib::Request& request, httplib::Response& response) const;
  std::string token_cookie() const { return "bosfuse_token_" + std::to_string(port); }
  void stream_events(const httplib::Request& request, httplib::Response& response);
  std::string snapshot_script();
  std::string read_stream(StreamState& state, const RunSnapshot& snapshot);
  bool stream_step(StreamState& state, httplib::DataSink& sink);

  ViewOptions options;
  std::string chartjs;
  RunWatch watch;
  LiveBos bos;
  GuardedServer server;
  const std::string token;                 // empty: none wanted
  std::vector<std::string> allowed_hosts;  // lowercase, as a Host header names them; empty: any
  int port = 0;
  std::atomic<int> clients{0};
  std::atomic<bool> stopping{false};
  std::atomic<bool> serving{false};
};

// The names a Host header may give: loopback's and the listening address,
// each with and without the port. Behind a wildcard address any name may
// reach the host, so any is let through — to the token, which it needs.
void LiveServer::Impl::admit_hosts_for(int listening_port) {
  std::vector<std::string> names{"localhost", "127.0.0.1", "[::1]"};
  if (is_wildcard_address(options.host)) return;
  const bool ipv6 = options.host.find(':') != std::string::npos;
  names.push_back(lowercase(ipv6 ? "[" + options.host + "]" : options.host));
  for (const std::string& name : names) {
    allowed_hosts.push_back(name);
    allowed_hosts.push_back(name + ":" + std::to_string(listening_port));
  }
}

// Every request, before its route: the Host check, then the token. A
// request that brings the token in its query gets it as a cookie, for the
// page's own requests (/api/run, /events, …); the name holds the port, as
// cookies do not tell ports apart and two viewers may run on one host.
bool LiveServer::Impl::admit(const httplib::Request& request, httplib::Response& response) const {
  const std::string host = lowercase(request.get_header_value("Host"));
  if (!allowed_hosts.empty() && std::find(allowed_hosts.begin(), allowed_hosts.end(), host) == allowed_hosts.end()) {
    refuse(response,
           "this viewer answers only to its own address (localhost, 127.0.0.1, [::1] or the one it "
           "listens on); the Host header named another, as a page of another site would");
    return false;
  }
  if (token.empty()) return true;
  if (same_secret(request.get_param_value("token"), token)) {
    response.set_header("Set-Cookie", token_cookie() + "=" + token + "; Path=/; HttpOnly; SameSite=Strict");
    return true;
  }
  if (same_secret(cookie_value(request, token_cookie()), token)) return true;
  refuse(response, "this viewer wants the token of its URL (http://HOST:PORT/?token=..., said when it started)");
  return false;
}

void LiveServer::Impl::route() {
  server.set_pre_routing_handler([this](const httplib::Request& request, httplib::Response& response) {
    return admit(request, response) ? httplib::Server::HandlerResponse::Unhandled
                                    : httplib::Server::HandlerResponse::Handled;
  });
  server.Get("/", [](const httplib::Request&, httplib::Response& response) {
    response.set_content(std::string(live_page_html()), "text/html; charset=utf-8");
  });
  server.Get("/chart.js", [this](const httplib::Request&, httplib::Response& response) {
    response.set_content(chartjs, "text/javascript; charset=utf-8");
  });
  server.Get("/api/run", [this](const httplib::Request&, httplib::Response& response) {
    try {
      response.set_content(watch.describe_json(), "application/json");
    } catch (const std::exception& e) {  // the run was damaged while served: say so, keep serving
      response.status = 500;
      response.set_content(nlohmann::json{{"error", unreadable_run_message(e)}}.dump(), "application/json");
    }
  });
  server.Get("/frame.png", [this](const httplib::Request&, httplib::Response& response) {
    const std::string png = bos.latest_frame_png();
    if (png.empty()) {
      response.status = 404;
      return;
    }
    response.set_content(png, "image/png");
  });
  server.Get("/snapshot.js", [this](const httplib::Request&, httplib::Response& response) {
    response.set_content(snapshot_script(), "text/javascript; charset=utf-8");
  });
  server.Get("/events", [this](const httplib::Request& request, httplib::Response& response) {
    stream_events(request, response);
  });
  // Every other path and method: 404 with a fixed body, nothing read.
  server.set_error_handler([](const httplib::Request&, httplib::Response& response) {
    if (response.status == 404) response.set_content("not found\n", "text/plain");
  });
  server.set_default_headers({{"X-Content-Type-Options", "nosniff"}, {"Cache-Control", "no-store"}});
}

// The page as it stands, for the page's first paint: a script the page
// loads before its own, so the chart is drawn with what the run holds before
// the document's load event (a headless screenshot, taken at that event,
// then shows the data). It is the first turn of a stream from the start,
// bounded like any (LiveStream::kRowsPerRead), and the cursor after it,
// from which the page's event stream goes on (`/events?after=`).
std::string LiveServer::Impl::snapshot_script() {
  nlohmann::json snapshot;
  try {
    LiveStream stream(watch.run_dir(), {}, &bos);
    const std::string text = stream.next(watch.snapshot());
    snapshot = {{"run", nlohmann::json::parse(watch.describe_json())},
                {"stream", text},
                {"cursor", format_cursor(stream.cursor())}};
  } catch (const std::exception& e) {  // the page says why and goes on with its stream
    snapshot = {{"error", unreadable_run_message(e)}};
  }
  return "window.bosfuseSnapshot = " + snapshot.dump() + ";\n";
}

// Where a stream starts: after the client's Last-Event-ID (a reconnect),
// else after the cursor its URL names (`?after=`, the page's snapshot),
// else at the run's beginning.
void LiveServer::Impl::stream_events(const httplib::Request& request, httplib::Response& response) {
  TailCursor from;
  const bool reconnect = request.has_header("Last-Event-ID");
  if (reconnect || request.has_param("after")) {
    const auto cursor =
        parse_cursor(reconnect ? request.get_header_value("Last-Event-ID") : request.get_param_value("after"));
    if (!cursor) {
      response.status = 400;
      response.set_content(std::string(reconnect ? "Last-Event-ID" : "after") + " is not an id this stream sent\n",
                           "text/plain");
      return;
    }
    from = *cursor;
  }
  if (clients.fetch_add(1) >= options.max_clients) {
    clients.fetch_sub(1);
    response.status = 503;
    response.set_content("too many open streams (at most " + std::to_string(options.max_clients) + ")\n",
                         "text/plain");
    return;
  }
  std::shared_ptr<StreamState> state;
  try {
    state = std::make_shared<StreamState>(watch.run_dir(), from, &bos);
  } catch (const std::exception& e) {
    clients.fetch_sub(1);
    response.status = 500;
    response.set_content(unreadable_run_message(e) + "\n", "text/plain");
    return;
  }
  response.set_header("X-Accel-Buffering", "no");
  response.set_chunked_content_provider(
      "text/event-stream",
      [this, state](std::size_t, httplib::DataSink& sink) {
        if (state->opening) {  // how long a browser waits before reconnecting
          state->opening = false;
          const std::string retry = "retry: 1000\n\n";
          if (!sink.write(retry.data(), retry.size())) return false;
        }
        return stream_step(*state, sink);
      },
      [this](bool) { clients.fetch_sub(1); });
}

// What the run says now, or, when it cannot be read several turns running
// (a busy store reads fine at the next turn; a damaged one never does), a
// `run-error` message once; an empty one when it reads again.
std::string LiveServer::Impl::read_stream(StreamState& state, const RunSnapshot& snapshot) {
  try {
    std::string text = state.stream.next(snapshot);
    if (!state.error_sent) return text;
    state.error_sent = false;
    return sse_message("run-error", "", R"({"error":""})") + text;
  } catch (const std::exception& e) {
    if (++state.failures < kFailuresBeforeError || state.error_sent) return {};
    state.error_sent = true;
    state.failures = 0;
    return sse_message("run-error", "", nlohmann::json{{"error", unreadable_run_message(e)}}.dump());
  }
}

// One turn of a stream: what is new, else a wait for the watch to see
// something (bounded, so stop() is noticed), else a keep-alive comment.
bool LiveServer::Impl::stream_step(StreamState& state, httplib::DataSink& sink) {
  // Also false once the client acknowledged nothing for the stall timeout:
  // a client that stopped reading gives its slot back.
  if (stopping || !sink.is_writable()) return false;
  const RunSnapshot snapshot = watch.snapshot();
  std::string text = read_stream(state, snapshot);
  const auto now = std::chrono::steady_clock::now();
  if (text.empty() && now - state.last_write >= kKeepAlivePeriod) text = ": keep-alive\n\n";
  if (!text.empty()) {
    state.last_write = now;
    return sink.write(text.data(), text.size());
  }
  watch.wait_for_change(snapshot.generation, options.poll_period * 5);
  return !stopping;
}

LiveServer::LiveServer(const std::filesystem::path& run_dir, ViewOptions options)
    : impl_(std::make_unique<Impl>(run_dir, std::move(options))) {}

LiveServer::~LiveServer() { stop(); }

int LiveServer::listen() {
  auto& server = impl_->server;
  const auto& options = impl_->options;
  errno = 0;
  if (options.port == 0) {
    impl_->port = server.bind_to_any_port(options.host);
    if (impl_->port < 0) throw ViewError("cannot listen on " + options.host + ": " + std::strerror(errno));
  } else {
    if (!server.bind_to_port(options.host, options.port)) {
      const std::string address = options.host + ":" + std::to_string(options.port);
      if (errno == EADDRINUSE) {
        throw ViewError("cannot listen on " + address + ": the port is in use (choose another with " + options.address_option + ")");
      }
      throw ViewError("cannot listen on " + address +
                      ": the port is in use, or the address is not one of this host's (" + std::strerror(errno) + ")");
    }
    impl_->port = options.port;
  }
  impl_->admit_hosts_for(impl_->port);
  return impl_->port;
}

std::string LiveServer::url() const {
  const std::string& host = impl_->options.host;
  const bool ipv6 = host.find(':') != std::string::npos;
  const std::string& token = impl_->token;
  return "http://" + (ipv6 ? "[" + host + "]" : host) + ":" + std::to_string(impl_->port) + "/" +
         (token.empty() ? "" : "?token=" + token);
}

void LiveServer::serve() {
  yield_to_the_logger();  // the accept loop runs on the caller's thread
  impl_->serving = true;
  if (impl_->stopping) return;
  impl_->server.listen_after_bind();
}

// httplib's stop() does nothing before its loop runs, so a stop that comes
// just after serve() began waits (briefly, bounded) for the loop to start.
void LiveServer::stop() {
  if (!impl_) return;
  impl_->stopping = true;
  for (int i = 0; i < 100 && impl_->serving && !impl_->server.is_running(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  impl_->server.stop();
}

}  // namespace bosfuse::view
