#include "fusion/displacement_field.h"

#include <gtest/gtest.h>

#include <sstream>

namespace bosfuse::fusion {
namespace {

TEST(DisplacementField, CsvHasTheHeaderAndOneLinePerVector) {
  DisplacementField field;
  field.rows = 1;
  field.cols = 2;
  field.vectors = {{7.5, 7.5, 0.25, -1.5, 3.2, VectorFlag::kOk, false, 0.0123, 0.00456},
                   {15.5, 7.5, 0, 0, 0, VectorFlag::kMasked}};
  std::ostringstream out;
  write_csv(field, out);
  EXPECT_EQ(out.str(),
            "x,y,u,v,valid,flag,peak_ratio,sigma_u,sigma_v\n"
            "7.5,7.5,0.25000,-1.50000,1,ok,3.200,0.01230,0.00456\n"
            "15.5,7.5,0.00000,0.00000,0,masked,0.000,0.00000,0.00000\n");
  EXPECT_EQ(field.count_valid(), 1u);
  EXPECT_EQ(field.count(VectorFlag::kMasked), 1u);
}

TEST(DisplacementField, FlagsHaveReadableNames) {
  EXPECT_EQ(to_string(VectorFlag::kOutlierReplaced), "outlier-replaced");
  EXPECT_EQ(to_string(VectorFlag::kNoTexture), "no-texture");
  EXPECT_EQ(to_string(VectorFlag::kOutOfRoi), "out-of-roi");
  EXPECT_EQ(to_string(VectorFlag::kNoPeak), "no-peak");
  EXPECT_EQ(to_string(VectorFlag::kBeyondSearch), "beyond-search");
  EXPECT_EQ(static_cast<int>(VectorFlag::kBeyondSearch), 6) << "stored values never change";
  for (int value = 0; value <= 6; ++value) {
    VectorFlag flag{};
    ASSERT_TRUE(parse_vector_flag(to_string(static_cast<VectorFlag>(value)), flag)) << value;
    EXPECT_EQ(static_cast<int>(flag), value);
  }
  VectorFlag flag{};
  EXPECT_FALSE(parse_vector_flag("beyond", flag));
}

}  // namespace
}  // namespace bosfuse::fusion
