#pragma once
// For tests: reads a Server-Sent Events text (what a client received) back
// into messages, the way a browser's EventSource splits it.

#include <sstream>
#include <string>
#include <vector>

namespace bosfuse::view::testing {

struct SseMessage {
  std::string type;
  std::string id;
  std::string data;
};

// Complete messages only: a trailing part without its blank line is left out.
inline std::vector<SseMessage> parse_sse(const std::string& text) {
  std::vector<SseMessage> messages;
  std::size_t start = 0;
  for (std::size_t end; (end = text.find("\n\n", start)) != std::string::npos; start = end + 2) {
    SseMessage message;
    std::istringstream lines(text.substr(start, end - start));
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("event: ", 0) == 0) message.type = line.substr(7);
      if (line.rfind("id: ", 0) == 0) message.id = line.substr(4);
      if (line.rfind("data: ", 0) == 0) message.data = line.substr(6);
    }
    if (!message.type.empty()) messages.push_back(std::move(message));
  }
  return messages;
}

}  // namespace bosfuse::view::testing
