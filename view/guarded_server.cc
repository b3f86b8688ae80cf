#include "view/guarded_server.h"

#include <arpa/inet.h>
#include <linux/sockios.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace bosfuse::view {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// How often a connection waiting for its next request looks whether the server stopped.
constexpr milliseconds kStopCheckPeriod{100};

// Rounded up, so a wait does not end just before its deadline.
milliseconds until(Clock::time_point deadline) {
  return std::max(milliseconds(0), std::chrono::ceil<milliseconds>(deadline - Clock::now()));
}

// poll() on one socket; true when it is ready for `events` (for reading:
// also when it was closed or failed, which the read then reveals).
bool wait_ready(socket_t sock, short events, milliseconds timeout) {
  pollfd p{sock, events, 0};
  int n;
  do {
    n = ::poll(&p, 1, static_cast<int>(timeout.count()));
  } while (n < 0 && errno == EINTR);
  if (n <= 0) return false;
  if (events == POLLOUT) return (p.revents & POLLOUT) && !(p.revents & (POLLERR | POLLHUP));
  return true;
}

// False once the client closed its side (a peek reads end of stream).
bool peer_open(socket_t sock) {
  char byte;
  const ssize_t n = ::recv(sock, &byte, 1, MSG_PEEK | MSG_DONTWAIT);
  return n > 0 || (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK));
}

void describe(const sockaddr_storage& address, std::string& ip, int& port) {
  char text[INET6_ADDRSTRLEN] = "";
  if (address.ss_family == AF_INET) {
    const auto& a = reinterpret_cast<const sockaddr_in&>(address);
    ::inet_ntop(AF_INET, &a.sin_addr, text, sizeof text);
    port = ntohs(a.sin_port);
  } else if (address.ss_family == AF_INET6) {
    const auto& a = reinterpret_cast<const sockaddr_in6&>(address);
    ::inet_ntop(AF_INET6, &a.sin6_addr, text, sizeof text);
    port = ntohs(a.sin6_port);
  }
  ip = text;
}

// One connection as httplib's Server reads and writes it (see the header).
class GuardedStream final : public httplib::Stream {
 public:
  GuardedStream(socket_t sock, const ConnectionLimits& limits) : sock_(sock), limits_(limits) {}

  // Waits for the next request's first byte and starts its deadline: false
  // after idle_timeout, or once the server stopped listening.
  bool await_request(const std::atomic<socket_t>& listening) {
    const auto idle_until = Clock::now() + limits_.idle_timeout;
    bool ready = begin_ < end_;  // a pipelined request is already here
    while (!ready && listening != INVALID_SOCKET && Clock::now() < idle_until) {
      ready = wait_ready(sock_, POLLIN, std::min(until(idle_until), kStopCheckPeriod));
    }
    request_deadline_ = Clock::now() + limits_.request_timeout;
    return ready && listening != INVALID_SOCKET;
  }

  // A wait for request bytes that fails can only have run out of time (a
  // closed or failed socket reads as ready): the connection ends. The
  // deadline is checked before waiting too, so bytes that keep trickling
  // in after it do not keep the request alive.
  bool is_readable() const override {
    if (begin_ < end_) return true;
    out_of_time_ = Clock::now() >= request_deadline_ || !wait_ready(sock_, POLLIN, until(request_deadline_));
    return !out_of_time_;
  }
  // The request did not arrive whole in time: httplib answers 400 and
  // would keep the connection for the next; it is closed instead.
  bool request_out_of_time() const { return out_of_time_; }

  // Buffered: httplib reads a request's line and headers a byte at a time.
  ssize_t read(char* ptr, size_t size) override {
    if (begin_ == end_) {
      if (!is_readable()) return -1;
      const ssize_t n = ::recv(sock_, buffer_.data(), buffer_.size(), 0);
      if (n <= 0) return n;
      begin_ = 0;
      end_ = static_cast<std::size_t>(n);
    }
    const std::size_t n = std::min(size, end_ - begin_);
    std::memcpy(ptr, buffer_.data() + begin_, n);
    begin_ += n;
    return static_cast<ssize_t>(n);
  }

  // Waits for room in the send buffer no longer than the client may go on
  // acknowledging nothing.
  bool is_writable() const override {
    if (client_stalled()) return false;
    return wait_ready(sock_, POLLOUT, until(last_progress_ + limits_.stall_timeout)) && peer_open(sock_);
  }

  ssize_t write(const char* ptr, size_t size) override {
    if (!is_writable()) return -1;
    const ssize_t n = ::send(sock_, ptr, size, MSG_NOSIGNAL);
    if (n > 0) expected_queue_ += static_cast<int>(n);
    return n;
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage address{};
    socklen_t length = sizeof address;
    if (::getpeername(sock_, reinterpret_cast<sockaddr*>(&address), &length) == 0) describe(address, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage address{};
    socklen_t length = sizeof address;
    if (::getsockname(sock_, reinterpret_cast<sockaddr*>(&address), &length) == 0) describe(address, ip, port);
  }
  socket_t socket() const override { return sock_; }

 private:
  // The client made progress when the bytes it has not acknowledged are
  // none, or fewer than were queued at the last look plus what was sent
  // since; stalled when it made none for stall_timeout.
  bool client_stalled() const {
    int queued = 0;
    if (::ioctl(sock_, SIOCOUTQ, &queued) != 0) return false;  // cannot tell: the socket's timeouts still hold
    const auto now = Clock::now();
    if (queued == 0 || queued < expected_queue_) last_progress_ = now;
    expected_queue_ = queued;
    return now - last_progress_ >= limits_.stall_timeout;
  }

  socket_t sock_;
  ConnectionLimits limits_;
  Clock::time_point request_deadline_ = Clock::now();
  mutable bool out_of_time_ = false;
  std::array<char, 4096> buffer_{};
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
  mutable Clock::time_point last_progress_ = Clock::now();
  mutable int expected_queue_ = 0;
};

}  // namespace

bool ConnectionLimits::valid() const {
  return idle_timeout.count() > 0 && request_timeout.count() > 0 && stall_timeout.count() > 0 &&
         requests_per_connection > 0;
}

GuardedServer::GuardedServer(ConnectionLimits limits) : limits_(limits) {
  if (!limits_.valid()) throw std::invalid_argument("connection limits: every timeout must be positive");
}

bool GuardedServer::listen_after_bind() {
  // httplib 0.11 listens with a backlog of 5: a sixth connection opened at
  // once waits for the client's SYN retry, a second or more, before it is
  // accepted. A second listen() on the socket only widens the queue.
  if (svr_sock_ != INVALID_SOCKET) ::listen(svr_sock_, SOMAXCONN);
  return httplib::Server::listen_after_bind();
}

bool GuardedServer::process_and_close_socket(socket_t sock) {
  bool ok = true;
  {
    GuardedStream stream(sock, limits_);
    for (std::size_t served = 0; served < limits_.requests_per_connection; ++served) {
      if (!stream.await_request(svr_sock_)) break;
      bool closed = false;
      ok = process_request(stream, served + 1 == limits_.requests_per_connection, closed, nullptr);
      if (!ok || closed || stream.request_out_of_time()) break;
    }
  }
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
  return ok;
}

}  // namespace bosfuse::view
