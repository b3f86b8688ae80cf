#include "storage/records.h"

#include "storage/database.h"

#include <array>
#include <stdexcept>
#include <string>

namespace bosfuse::storage {
namespace {

constexpr std::array<std::string_view, 3> kRunStatusNames = {"running", "complete", "interrupted"};
constexpr std::array<std::string_view, kSampleStatusCount> kSampleStatusNames = {
    "ok", "open-circuit", "out-of-range", "timeout", "bad-reply", "invalid-value", "disabled"};

}  // namespace

std::string_view to_string(RunStatus status) { return kRunStatusNames.at(static_cast<int>(status)); }

RunStatus run_status_from_string(std::string_view text) {
  for (std::size_t i = 0; i < kRunStatusNames.size(); ++i) {
    if (kRunStatusNames[i] == text) return static_cast<RunStatus>(i);
  }
  throw std::invalid_argument("unknown run status '" + std::string(text) + "'");
}

std::string_view to_string(SampleStatus status) { return kSampleStatusNames.at(static_cast<int>(status)); }

SampleStatus sample_status_from_code(std::int64_t code) {
  if (code < 0 || code >= kSampleStatusCount) {
    throw StorageError("a sample has status code " + std::to_string(code) + ", which no status has (0.." +
                       std::to_string(kSampleStatusCount - 1) + "): the run store is damaged");
  }
  return static_cast<SampleStatus>(code);
}

}  // namespace bosfuse::storage
