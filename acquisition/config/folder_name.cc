#include "acquisition/config/folder_name.h"

namespace bosfuse::acquisition {
namespace {

bool portable(unsigned char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
}

}  // namespace

std::string folder_name_problem(std::string_view name) {
  if (name.empty()) return "must not be empty";
  if (name.size() > kMaxFolderNameBytes) {
    return "is " + std::to_string(name.size()) + " bytes long, more than the " + std::to_string(kMaxFolderNameBytes) +
           " a folder name may have";
  }
  for (const unsigned char c : name) {
    if (!portable(c)) return "may use only letters, digits, - and _";
  }
  return {};
}

}  // namespace bosfuse::acquisition
