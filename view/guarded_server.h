#pragma once
// GuardedServer is cpp-httplib's Server with the time limits a page served
// on a user's machine needs against clients that hold on to its threads.
// httplib (0.11, Debian 12's) gives each connection a thread of its pool and
// times out each read and each write on its own: a request trickled in a
// byte a second never times out, and a stream to a client that stopped
// reading goes on for minutes while the socket buffers absorb what is sent.
// Here every connection is served through a stream of its own (httplib's
// Stream, which its Server reads requests from and writes answers to) that
// - waits at most `idle_timeout` for a request to begin, the first or the
//   next one on a kept-alive connection;
// - gives a request's line, headers and body `request_timeout` in all from
//   its first byte, however slowly they come;
// - fails its writes, and says it is not writable, once the client has
//   acknowledged nothing of what was sent for `stall_timeout` (the socket's
//   unacknowledged bytes, SIOCOUTQ, did not go down): a streaming handler
//   that asks `sink.is_writable()` ends and frees its slot.
//
// Use: as httplib::Server (routes, handlers, bind, listen); the limits are
// given at construction. A live stream whose client reads keeps going: only
// the request phase has a total deadline.

#include <httplib.h>

#include <chrono>
#include <cstddef>

namespace bosfuse::view {

struct ConnectionLimits {
  std::chrono::milliseconds idle_timeout{5000};
  std::chrono::milliseconds request_timeout{5000};
  std::chrono::milliseconds stall_timeout{5000};
  std::size_t requests_per_connection = 100;
  // Each timeout positive, at least one request per connection.
  bool valid() const;
};

class GuardedServer : public httplib::Server {
 public:
  // Throws std::invalid_argument for limits that are not valid().
  explicit GuardedServer(ConnectionLimits limits);

  // httplib's, with a listen queue of SOMAXCONN instead of its 5, so a
  // burst of connections (a page's, or a client holding many) is accepted
  // at once. Hides httplib::Server's: call it on a GuardedServer.
  bool listen_after_bind();

 private:
  // httplib's per-connection entry point (run on a pool thread): the
  // keep-alive loop over process_request(), with the limits above.
  bool process_and_close_socket(socket_t sock) override;

  ConnectionLimits limits_;
};

}  // namespace bosfuse::view
