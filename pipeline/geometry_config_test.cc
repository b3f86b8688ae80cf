#include "pipeline/geometry_config.h"

#include <gtest/gtest.h>

#include "pipeline/processing_settings.h"

namespace bosfuse::pipeline {
namespace {

std::string error_of(const std::string& toml) {
  try {
    parse_geometry_config(toml, "g.toml");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(GeometryUncertainty, IsReadFromItsTableAndDefaultsWhereNotGiven) {
  const auto config = parse_geometry_config(
      "[geometry]\nz_d_m = 0.4\n\n[geometry.uncertainty]\nz_d_relative = 0.02\ndepth_relative = 0.1\n"
      "ambient_pressure_pa = 50\n",
      "g.toml");
  ASSERT_TRUE(config);
  EXPECT_DOUBLE_EQ(config->uncertainty.z_d_relative, 0.02);
  EXPECT_DOUBLE_EQ(config->uncertainty.depth_relative, 0.1);
  EXPECT_DOUBLE_EQ(config->uncertainty.ambient_pressure_pa, 50);
  const fusion::TypeBUncertainties defaults;
  EXPECT_DOUBLE_EQ(config->uncertainty.magnification_relative, defaults.magnification_relative);
  EXPECT_DOUBLE_EQ(config->uncertainty.ambient_temperature_c, defaults.ambient_temperature_c);
}

TEST(GeometryUncertainty, ErrorsNameTheKeyAndTheLine) {
  EXPECT_EQ(error_of("[geometry]\n[geometry.uncertainty]\nz_d = 0.01\n"),
            "g.toml:3: geometry.uncertainty.z_d: unknown key (a typo?)");
  EXPECT_NE(error_of("[geometry]\n[geometry.uncertainty]\n\ndepth_relative = -0.1\n").find("g.toml:4"),
            std::string::npos);
  EXPECT_NE(error_of("[geometry.uncertainty]\nz_d_relative = 2\n").find("geometry.uncertainty.z_d_relative"),
            std::string::npos);
}

TEST(GeometryUncertainty, TravelsWithTheStoredSettingsAndOlderSettingsGetTheDefaults) {
  ProcessingSettings settings;
  settings.geometry.uncertainty.z_d_relative = 0.03;
  settings.geometry.uncertainty.gladstone_dale_relative = 0.004;
  const auto back = settings_from_json(nlohmann::json::parse(to_json(settings).dump()));
  EXPECT_DOUBLE_EQ(back.geometry.uncertainty.z_d_relative, 0.03);
  EXPECT_DOUBLE_EQ(back.geometry.uncertainty.gladstone_dale_relative, 0.004);
  auto older = nlohmann::json::parse(to_json(settings).dump());
  older.at("geometry").erase("uncertainty");
  EXPECT_DOUBLE_EQ(settings_from_json(older).geometry.uncertainty.z_d_relative,
                   fusion::TypeBUncertainties{}.z_d_relative);
}

}  // namespace
}  // namespace bosfuse::pipeline
