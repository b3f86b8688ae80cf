// GuardedServer's limits with short timeouts, on a loopback port chosen at
// run time: what is cut off, and what is not (a slow client that reads).

#include "view/guarded_server.h"

#include <gtest/gtest.h>

#include <thread>

#include "tests/support/subprocess.h"
#include "view/test_raw_connection.h"

namespace bosfuse::view {
namespace {

using namespace std::chrono_literals;
using testing::RawConnection;

constexpr std::size_t kStreamBytes = 512 * 1024;
constexpr std::size_t kEndlessBytes = 64 * 1024 * 1024;

// Sends `total` bytes in 4 KiB pieces, asking is_writable() before each.
httplib::Server::Handler stream_of(std::size_t total) {
  return [total](const httplib::Request&, httplib::Response& response) {
    response.set_chunked_content_provider("application/octet-stream",
                                          [total](std::size_t offset, httplib::DataSink& sink) {
                                            if (offset >= total) {
                                              sink.done();
                                              return true;
                                            }
                                            const std::string piece(4096, 'x');
                                            return sink.is_writable() && sink.write(piece.data(), piece.size());
                                          });
  };
}

// A GuardedServer with 400 ms limits and two routes: /stream sends
// kStreamBytes, /endless more than any socket buffers hold.
class Guarded : public ::testing::Test {
 protected:
  void SetUp() override {
    server_.Get("/stream", stream_of(kStreamBytes));
    server_.Get("/endless", stream_of(kEndlessBytes));
    port_ = server_.bind_to_any_port("127.0.0.1");
    ASSERT_GT(port_, 0);
    serving_ = std::thread([this] { server_.listen_after_bind(); });
    ASSERT_TRUE(bosfuse::testing::wait_for([&] { return server_.is_running(); }, 5s));
  }
  void TearDown() override {
    server_.stop();
    if (serving_.joinable()) serving_.join();
  }

  GuardedServer server_{{.idle_timeout = 400ms, .request_timeout = 400ms, .stall_timeout = 400ms}};
  int port_ = 0;
  std::thread serving_;
};

TEST(ConnectionLimits, WantsPositiveTimeoutsAndAtLeastOneRequest) {
  EXPECT_TRUE(ConnectionLimits{}.valid());
  EXPECT_THROW(GuardedServer({.idle_timeout = 0ms}), std::invalid_argument);
  EXPECT_THROW(GuardedServer({.stall_timeout = -1ms}), std::invalid_argument);
  EXPECT_THROW(GuardedServer({.requests_per_connection = 0}), std::invalid_argument);
}

// The stall timeout is about acknowledging nothing, not about speed: a
// client that reads 2 KiB every 20 ms or so through a small receive buffer
// (far slower than the server sends) gets the whole stream.
TEST_F(Guarded, KeepsStreamingToAClientThatReadsSlowlyButSteadily) {
  RawConnection slow("127.0.0.1", port_, 4096);
  ASSERT_TRUE(slow.connected());
  ASSERT_TRUE(slow.send_text("GET /stream HTTP/1.1\r\nHost: x\r\n\r\n"));
  std::size_t received = 0;
  for (int i = 0; i < 2000 && received < kStreamBytes; ++i) {  // bounded: about 60 s at most
    std::this_thread::sleep_for(20ms);
    received += slow.read_up_to(2048, 1000);
  }
  EXPECT_GE(received, kStreamBytes) << "the stream was cut off after " << received << " bytes";
}

// A client that stops reading halfway is dropped once 400 ms pass without
// it acknowledging anything: it sees the end of the connection.
TEST_F(Guarded, DropsAClientThatStopsReading) {
  RawConnection stopped("127.0.0.1", port_, 4096);
  ASSERT_TRUE(stopped.send_text("GET /endless HTTP/1.1\r\nHost: x\r\n\r\n"));
  ASSERT_GT(stopped.read_up_to(1000, 2000), 0u);
  std::this_thread::sleep_for(1500ms);  // reads nothing: the server's writes stall, then fail
  for (int i = 0; i < 4000 && !stopped.ended(); ++i) stopped.read_up_to(65536, 1000);  // what the buffers held
  EXPECT_TRUE(stopped.ended());
  EXPECT_LT(stopped.received().size(), kEndlessBytes / 4) << "the server went on writing";
}

// A request trickled in is cut off at its deadline however steadily it
// comes; one that never begins, at the idle timeout.
TEST_F(Guarded, CutsOffARequestThatTricklesAndAConnectionThatSaysNothing) {
  RawConnection trickling("127.0.0.1", port_);
  RawConnection silent("127.0.0.1", port_);
  ASSERT_TRUE(trickling.send_text("GET /stream HTTP/1.1\r\n"));
  const auto start = std::chrono::steady_clock::now();
  bool trickling_cut = false, silent_cut = false;
  for (int i = 0; i < 40 && !(trickling_cut && silent_cut); ++i) {  // bounded: 2 s
    std::this_thread::sleep_for(50ms);
    trickling_cut = trickling_cut || trickling.closed_by_server() || !trickling.send_text("X");
    silent_cut = silent_cut || silent.closed_by_server();
  }
  EXPECT_TRUE(trickling_cut);
  EXPECT_TRUE(silent_cut);
  EXPECT_LT(std::chrono::steady_clock::now() - start, 1500ms);
}

}  // namespace
}  // namespace bosfuse::view
