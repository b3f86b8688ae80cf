#include "fusion/displacement_field.h"

#include <algorithm>
#include <ostream>
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
    case VectorFlag::kBeyondSearch:
      return "beyond-search";
  }
  return "unknown";
}

bool parse_vector_flag(std::string_view name, VectorFlag& flag) {
  for (int value = 0; value <= static_cast<int>(VectorFlag::kBeyondSearch); ++value) {
    if (to_string(static_cast<VectorFlag>(value)) == name) {
      flag = static_cast<VectorFlag>(value);
      return true;
    }
  }
  return false;
}

std::size_t DisplacementField::count(VectorFlag flag) const {
  return static_cast<std::size_t>(
      std::count_if(vectors.begin(), vectors.end(), [flag](const auto& v) { return v.flag == flag; }));
}

namespace {

FieldCsvWriter field_text(const DisplacementField& field) {
  FieldCsvWriter csv(kDisplacementColumns, field.vectors.size());
  for (const auto& v : field.vectors) {
    // Enough digits for 0.001 px work; the centre is exact in half pixels.
    csv.fixed(v.x_px, 1);
    csv.fixed(v.y_px, 1);
    csv.fixed(v.u_px, 5);
    csv.fixed(v.v_px, 5);
    csv.integer(v.valid() ? 1 : 0);
    csv.text(to_string(v.flag));
    csv.fixed(v.peak_ratio, 3);
    csv.fixed(v.sigma_u_px, 5);
    csv.fixed(v.sigma_v_px, 5);
    csv.end_line();
  }
  return csv;
}

}  // namespace

void write_csv(const DisplacementField& field, std::ostream& out) {
  const FieldCsvWriter csv = field_text(field);
  const std::string_view text = csv.text();
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
}

void write_csv(const DisplacementField& field, const std::filesystem::path& path) { field_text(field).save(path); }

}  // namespace bosfuse::fusion
