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
  }
  return "unknown";
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
