#include "fusion/displacement_field.h"

#include <algorithm>
#include <stdexcept>


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

}  // namespace bosfuse::fusion
