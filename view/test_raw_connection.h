#pragma once
// For tests: a bare TCP connection to a loopback port, for the clients no
// HTTP library would be — one that trickles its request, one that never
// reads what it is sent.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <string>

namespace bosfuse::view::testing {

class RawConnection {
 public:
  // `receive_buffer` > 0: SO_RCVBUF before connecting, so a client that
  // does not read fills it (and closes the server's window) quickly.
  RawConnection(const std::string& host, int port, int receive_buffer = 0) : fd_(socket(AF_INET, SOCK_STREAM, 0)) {
    if (receive_buffer > 0) setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<std::uint16_t>(port));
    inet_pton(AF_INET, host.c_str(), &address.sin_addr);
    connected_ = connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  }
  ~RawConnection() { close(fd_); }
  RawConnection(const RawConnection&) = delete;
  RawConnection& operator=(const RawConnection&) = delete;

  bool connected() const { return connected_; }
  bool send_text(const std::string& text) {
    return send(fd_, text.data(), text.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(text.size());
  }
  // Reads at most `bytes` once something comes within `timeout_ms`; how many (0: none, or closed).
  std::size_t read_up_to(std::size_t bytes, int timeout_ms) {
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0) return 0;
    std::string buffer(bytes, '\0');
    const ssize_t n = recv(fd_, buffer.data(), bytes, 0);
    ended_ = ended_ || n == 0;
    if (n <= 0) return 0;
    received_.append(buffer, 0, static_cast<std::size_t>(n));
    return static_cast<std::size_t>(n);
  }
  // Reads what has come (without waiting); true once the server closed the connection.
  bool closed_by_server() {
    char buffer[4096];
    for (int i = 0; i < 1000; ++i) {
      const ssize_t n = recv(fd_, buffer, sizeof buffer, MSG_DONTWAIT);
      if (n == 0) return true;
      if (n < 0) return errno != EAGAIN && errno != EWOULDBLOCK;
      received_.append(buffer, static_cast<std::size_t>(n));
    }
    return false;
  }
  const std::string& received() const { return received_; }
  // read_up_to() met the end of the connection.
  bool ended() const { return ended_; }
  // Whether what has come starts with `prefix`, looked at without reading it.
  bool peek_starts_with(const std::string& prefix) {
    std::string buffer(prefix.size(), '\0');
    const ssize_t n = recv(fd_, buffer.data(), buffer.size(), MSG_PEEK | MSG_DONTWAIT);
    return n == static_cast<ssize_t>(prefix.size()) && buffer == prefix;
  }

 private:
  int fd_;
  bool connected_ = false;
  bool ended_ = false;
  std::string received_;
};

}  // namespace bosfuse::view::testing
