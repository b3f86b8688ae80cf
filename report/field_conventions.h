#pragma once
// The words every field file bosfuse writes carries about its numbers (a
// run's export, field_export.h; a sequence's, sequence_export.h), one text
// for both, so a reader of one file reads the other alike.

#include <string>
#include <string_view>

namespace bosfuse::report {

inline constexpr std::string_view kDisplacementConvention =
    "a background feature at (x, y) in the reference image appears at (x + u, y + v) in the measurement image";

// `arrays` says how the file's arrays are laid out, e.g. "2-D arrays are [ny, nx]".
inline std::string coordinates_convention(std::string_view arrays) {
  return "image coordinates: origin at the top-left pixel's centre, x to the right, y down; " + std::string(arrays) +
         " (row index = y)";
}

}  // namespace bosfuse::report
