#include "fusion/displacement_field.h"

#include <gtest/gtest.h>


namespace bosfuse::fusion {
namespace {

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
