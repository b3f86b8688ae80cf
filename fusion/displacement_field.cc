#include "fusion/displacement_field.h"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "fusion/field_csv.h"

namespace bosfuse::fusion {

std::string to_string(VectorFlag flag) {
  switch (flag) {
    case VectorFlag::kOk:
      return "ok";
    case VectorFlag::kOutlierReplaced:
      return "outlier-replaced";
    case VectorFlag::kNoTexture:
      return "no-texture";
    case VectorFlag::kMasked:
      return "masked";
    case VectorFlag::kOutOfRoi:
      return "out-of-roi";
    case VectorFlag::kNoPeak:
      return "no-peak";
  }
  return "unknown";
}

std::size_t DisplacementField::count(VectorFlag flag) const {
  return static_cast<std::size_t>(
      std::count_if(vectors.begin(), vectors.end(), [flag](const auto& v) { return v.flag == flag; }));
}

void write_csv(const DisplacementField& field, std::ostream& out) {
  // Formatted into one buffer: a 16 MP field has 250 k rows, and a string
  // and a stream insertion per row cost more than the formatting itself.
  fmt::memory_buffer text;
  const auto to = std::back_inserter(text);
  fmt::format_to(to, "{}\n", field_csv_header(kDisplacementColumns));
  for (const auto& v : field.vectors) {
    // Enough digits for 0.001 px work; the centre is exact in half pixels.
    fmt::format_to(to, "{:.1f},{:.1f},{:.5f},{:.5f},{},{:.3f}\n", v.x_px, v.y_px, v.u_px, v.v_px, v.valid() ? 1 : 0,
                   v.peak_ratio);
  }
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
}

void write_csv(const DisplacementField& field, const std::filesystem::path& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot open for writing");
  write_csv(field, out);
  if (!out.flush()) throw std::runtime_error(path.string() + ": write failed");
}

}  // namespace bosfuse::fusion
