#pragma once
// The whole content of a file, byte for byte (binary mode), for tests that
// compare what a command wrote or left alone. A missing file reads as "".

#include <filesystem>
#include <fstream>
#include <cstdint>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace bosfuse::testing {

inline std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// The same as bytes, for code that reads a file's bytes as std::uint8_t.
inline std::vector<std::uint8_t> file_byte_vector(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace bosfuse::testing
