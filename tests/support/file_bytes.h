#pragma once
// The whole content of a file, byte for byte (binary mode), for tests that
// compare what a command wrote or left alone. A missing file reads as "".

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace bosfuse::testing {

inline std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

}  // namespace bosfuse::testing
