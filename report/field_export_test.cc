#include "report/field_export.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "pipeline/field_csv.h"
#include "pipeline/process.h"
#include "storage/experiment_clock.h"
#include "report/hdf5_writer.h"
#include "report/test_readers.h"
#include "tests/support/synthetic_run.h"
#include "storage/processing_store.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// ---- the HDF5 C API as a reader, in-process -------------------------------

struct Array {
  std::vector<hsize_t> dims;
  std::vector<double> values;
};

Array read_array(hid_t file, const std::string& path, hid_t memory_type = H5T_NATIVE_DOUBLE) {
  hdf5::Dataset dataset(H5Dopen2(file, path.c_str(), H5P_DEFAULT));
  if (!dataset.valid()) throw std::runtime_error("no dataset " + path);
  hdf5::Dataspace space(H5Dget_space(dataset.get()));
  Array out;
  out.dims.resize(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space.get())));
  H5Sget_simple_extent_dims(space.get(), out.dims.data(), nullptr);
  const auto n = static_cast<std::size_t>(H5Sget_simple_extent_npoints(space.get()));
  if (memory_type == H5T_NATIVE_UINT8) {
    std::vector<std::uint8_t> bytes(n);
    H5Dread(dataset.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data());
    out.values.assign(bytes.begin(), bytes.end());
  } else {
    out.values.resize(n);
    H5Dread(dataset.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.values.data());
  }
  return out;
}

hid_t stored_type(hid_t file, const std::string& path) {
  hdf5::Dataset dataset(H5Dopen2(file, path.c_str(), H5P_DEFAULT));
  hdf5::Datatype type(H5Dget_type(dataset.get()));
  if (H5Tequal(type.get(), H5T_IEEE_F64LE) > 0) return H5T_IEEE_F64LE;
  if (H5Tequal(type.get(), H5T_STD_U8LE) > 0) return H5T_STD_U8LE;
  return H5I_INVALID_HID;
}

std::string string_attribute(hid_t file, const std::string& object, const std::string& name) {
  hdf5::Attribute attribute(H5Aopen_by_name(file, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT));
  if (!attribute.valid()) throw std::runtime_error("no attribute " + object + "@" + name);
  hdf5::Datatype type(H5Aget_type(attribute.get()));
  EXPECT_GT(H5Tis_variable_str(type.get()), 0) << object << "@" << name;
  EXPECT_EQ(H5Tget_cset(type.get()), H5T_CSET_UTF8);
  char* text = nullptr;
  H5Aread(attribute.get(), type.get(), &text);
  std::string out = text ? text : "";
  H5free_memory(text);
  return out;
}

template <typename T>
T number_attribute(hid_t file, const std::string& object, const std::string& name) {
  hdf5::Attribute attribute(H5Aopen_by_name(file, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT));
  if (!attribute.valid()) throw std::runtime_error("no attribute " + object + "@" + name);
  T value{};
  H5Aread(attribute.get(), std::is_same_v<T, double> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64, &value);
  return value;
}

// ---- a run with fields stored by hand, every value known ------------------

constexpr int kRows = 3, kCols = 4;

std::string displacement_csv(int k) {
  std::string text = "x,y,u,v,valid,peak_ratio\n";
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kCols; ++c) {
      const int i = r * kCols + c;
      text += fmt::format("{:.1f},{:.1f},{:.5f},{:.5f},{},{:.3f}\n", 8.0 + 8 * c, 8.0 + 8 * r, 0.01 * i + k, -0.02 * i,
                          i == 5 ? 0 : 1, 1.5 + 0.125 * i);
    }
  }
  return text;
}

std::string temperature_csv(int k) {
  std::string text = "x,y,temperature_c,measured,sigma_c\n";
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kCols; ++c) {
      const bool missing = r == 1 && c == 2;
      const bool filled = r == 0 && c == 1;  // a temperature the solve filled in: not a measurement
      text += fmt::format("{:.1f},{:.1f},{},{},{}\n", 8.0 + 8 * c, 8.0 + 8 * r,
                          missing ? "nan" : fmt::format("{:.4f}", 30 + r + 0.25 * c + k), missing || filled ? 0 : 1,
                          missing ? "nan" : "0.01000");
    }
  }
  return text;
}

double expected_u(int k, int i) { return std::stod(fmt::format("{:.5f}", 0.01 * i + k)); }

class FieldExport : public ::testing::Test {
 protected:
  void SetUp() override {
    testrun::create_run(run(), true, truth_);
    const auto store = storage::RunStore::open(run());
    frames_ = store.frames();
    ASSERT_EQ(frames_.size(), 3u);
  }
  fs::path run() const { return dir_ / "run"; }
  // Fields for the two measurement frames, stored as `bosfuse process` would.
  void store_fields() {
    storage::ProcessingStore results(run(), true);
    fs::create_directories(run() / "fields");
    for (int k = 0; k < 2; ++k) {
      const auto& frame = frames_[1 + k];
      const std::string stem = fmt::format("fields/frame_{:06d}", frame.id);
      std::ofstream(run() / (stem + "_displacement.csv")) << displacement_csv(k);
      std::ofstream(run() / (stem + "_temperature.csv")) << temperature_csv(k);
      results.add_field({0, frame.id, "displacement", stem + "_displacement.csv", R"({"method":"test"})"});
      results.add_field({0, frame.id, "temperature", stem + "_temperature.csv", "{}"});
    }
  }
  std::string group(const char* kind, int k) const { return fmt::format("/{}/frame_{:06d}", kind, frames_[1 + k].id); }
  FieldExportResult export_to(const fs::path& out, std::optional<double> px_per_mm = 30.0) {
    FieldExportOptions options;
    options.px_per_mm = px_per_mm;
    return export_fields(storage::RunStore::open(run()), out, options);
  }

  testing::TempDir dir_;
  testrun::Truth truth_;
  std::vector<storage::FrameRecord> frames_;
};

TEST_F(FieldExport, KnownFieldsRoundTripThroughTheHdf5CApi) {
  store_fields();
  const auto result = export_to(dir_ / "fields.h5");
  EXPECT_EQ(result.displacement_frames, 2u);
  EXPECT_EQ(result.temperature_frames, 2u);
  EXPECT_EQ(result.grids, 1u) << "one grid, stored once";
  EXPECT_EQ(result.xdmf_path, dir_ / "fields.xmf");

  hdf5::File file(H5Fopen((dir_ / "fields.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  ASSERT_TRUE(file.valid());
  const hid_t f = file.get();
  EXPECT_EQ(string_attribute(f, "/", "run_name"), "synthetic cooling");
  EXPECT_EQ(string_attribute(f, "/", "bosfuse_version"), "0.1.0");
  EXPECT_NE(string_attribute(f, "/", "displacement_convention").find("(x + u, y + v)"), std::string::npos);
  EXPECT_NE(string_attribute(f, "/", "time").find("experiment seconds since the first sample"), std::string::npos);
  EXPECT_EQ(number_attribute<double>(f, "/", "px_per_mm"), 30.0);
  EXPECT_EQ(number_attribute<std::int64_t>(f, "/", "layout_version"), 2) << "2: NaN where not measured";

  const auto clock = storage::experiment_clock(storage::RunStore::open(run()));
  for (int k = 0; k < 2; ++k) {
    const std::string d = group("displacement", k);
    EXPECT_EQ(number_attribute<double>(f, d, "t_s"), clock.seconds(frames_[1 + k].t_ns));
    EXPECT_NEAR(number_attribute<double>(f, d, "t_s"), truth_.frame_times_s[k] + 0.003, 1e-9);
    EXPECT_EQ(number_attribute<std::int64_t>(f, d, "frame_id"), frames_[1 + k].id);
    EXPECT_EQ(string_attribute(f, d, "frame_path"), frames_[1 + k].path);
    EXPECT_EQ(string_attribute(f, d, "summary"), R"({"method":"test"})");
    const auto u = read_array(f, d + "/u_px");
    ASSERT_EQ(u.dims, (std::vector<hsize_t>{kRows, kCols})) << "[ny, nx]";
    EXPECT_EQ(stored_type(f, d + "/u_px"), H5T_IEEE_F64LE);
    for (int i = 0; i < kRows * kCols; ++i) {
      if (i == 5) continue;
      EXPECT_EQ(u.values[i], expected_u(k, i)) << "node " << i << ", exactly";
    }
    for (const char* name : {"/u_px", "/v_px", "/peak_ratio"}) {
      EXPECT_TRUE(std::isnan(read_array(f, d + name).values[5])) << name << ": not measured (valid 0) is NaN";
    }
    EXPECT_EQ(read_array(f, d + "/v_px").values[7], std::stod(fmt::format("{:.5f}", -0.14)));
    const auto valid = read_array(f, d + "/valid", H5T_NATIVE_UINT8);
    EXPECT_EQ(stored_type(f, d + "/valid"), H5T_STD_U8LE);
    EXPECT_EQ(valid.values[5], 0);
    EXPECT_EQ(valid.values[6], 1);
    EXPECT_EQ(read_array(f, d + "/peak_ratio").values[4], 2.0);
    EXPECT_EQ(string_attribute(f, d + "/u_px", "units"), "px");
    EXPECT_EQ(string_attribute(f, d + "/valid", "units"), "1");
    EXPECT_EQ(string_attribute(f, d + "/peak_ratio", "units"), "1");

    const std::string t = group("temperature", k);
    const auto temperature = read_array(f, t + "/temperature_c");
    ASSERT_EQ(temperature.dims, (std::vector<hsize_t>{kRows, kCols}));
    EXPECT_EQ(temperature.values[0 * kCols + 3], 30.75 + k);
    EXPECT_EQ(temperature.values[2 * kCols + 1], 32.25 + k) << "row = y";
    EXPECT_TRUE(std::isnan(temperature.values[1 * kCols + 2])) << "no temperature: NaN";
    EXPECT_EQ(read_array(f, t + "/measured", H5T_NATIVE_UINT8).values[1 * kCols + 2], 0);
    EXPECT_TRUE(std::isnan(temperature.values[0 * kCols + 1])) << "filled in by the solve: NaN";
    EXPECT_EQ(read_array(f, t + "/measured", H5T_NATIVE_UINT8).values[0 * kCols + 1], 0) << "and flagged";
    EXPECT_EQ(read_array(f, t + "/measured", H5T_NATIVE_UINT8).values[0 * kCols + 0], 1);
    EXPECT_EQ(string_attribute(f, t + "/temperature_c", "units"), "degC");
    EXPECT_EQ(string_attribute(f, t + "/measured", "units"), "1");
    EXPECT_EQ(number_attribute<double>(f, t, "t_s"), number_attribute<double>(f, d, "t_s"));

    // The grid, through the links in the frame's group.
    EXPECT_EQ(read_array(f, d + "/x_px").values, (std::vector<double>{8, 16, 24, 32}));
    EXPECT_EQ(read_array(f, t + "/y_px").values, (std::vector<double>{8, 16, 24}));
    EXPECT_EQ(read_array(f, d + "/x_mm").values[3], 32.0 / 30.0);
    EXPECT_EQ(string_attribute(f, d + "/y_mm", "units"), "mm");
    EXPECT_EQ(string_attribute(f, d, "grid"), "/grids/grid_000");
  }
  const auto times = read_array(f, "/temperature/t_s");
  ASSERT_EQ(times.dims, (std::vector<hsize_t>{2}));
  EXPECT_LT(times.values[0], times.values[1]) << "in time order";
  EXPECT_EQ(string_attribute(f, "/temperature/t_s", "units"), "s");
  EXPECT_EQ(read_array(f, "/displacement/frame_id", H5T_NATIVE_INT64).dims, (std::vector<hsize_t>{2}));
}

TEST_F(FieldExport, H5pyReadsShapesValuesUnitsAndTimes) {
  store_fields();
  export_to(dir_ / "fields.h5");
  const json h5 = testreaders::h5py_listing(dir_ / "fields.h5", dir_.path());
  EXPECT_EQ(h5.at("/").at("attrs").at("run_name"), "synthetic cooling");
  EXPECT_EQ(h5.at("/").at("attrs").at("bosfuse_version"), "0.1.0");
  for (int k = 0; k < 2; ++k) {
    const json& g = h5.at(group("displacement", k));
    EXPECT_EQ(g.at("kind"), "group");
    EXPECT_NEAR(g.at("attrs").at("t_s").get<double>(), truth_.frame_times_s[k] + 0.003, 1e-9);
    EXPECT_EQ(g.at("attrs").at("frame_id"), frames_[1 + k].id);
    const json& u = h5.at(group("displacement", k) + "/u_px");
    EXPECT_EQ(u.at("shape"), json::array({kRows, kCols}));
    EXPECT_EQ(u.at("dtype"), "float64");
    EXPECT_EQ(u.at("attrs").at("units"), "px");
    EXPECT_EQ(u.at("compression"), "gzip");
    EXPECT_EQ(u.at("compression_opts"), 4);
    for (int i = 0; i < kRows * kCols; ++i) {
      if (i == 5) {
        EXPECT_TRUE(u.at("data")[i].is_null()) << "NaN where valid is 0";
      } else {
        EXPECT_EQ(u.at("data")[i].get<double>(), expected_u(k, i));
      }
    }
    const json& valid = h5.at(group("displacement", k) + "/valid");
    EXPECT_EQ(valid.at("dtype"), "uint8");
    EXPECT_EQ(valid.at("data")[5], 0);
    const json& t = h5.at(group("temperature", k) + "/temperature_c");
    EXPECT_EQ(t.at("shape"), json::array({kRows, kCols}));
    EXPECT_EQ(t.at("attrs").at("units"), "degC");
    EXPECT_TRUE(t.at("data")[1 * kCols + 2].is_null()) << "NaN where no temperature";
    EXPECT_EQ(t.at("data")[0].get<double>(), 30.0 + k);
    EXPECT_EQ(h5.at(group("temperature", k) + "/x_mm").at("kind"), "softlink");
    EXPECT_EQ(h5.at(group("temperature", k) + "/x_mm").at("target"), "/grids/grid_000/x_mm");
  }
  EXPECT_EQ(h5.at("/grids/grid_000/x_mm").at("shape"), json::array({kCols}));
  EXPECT_EQ(h5.at("/grids/grid_000/y_px").at("data"), json::array({8.0, 16.0, 24.0}));
  EXPECT_EQ(h5.at("/grids/grid_000/x_mm").at("attrs").at("units"), "mm");
  EXPECT_EQ(h5.at("/displacement/t_s").at("attrs").at("units"), "s");
  EXPECT_EQ(h5.at("/displacement/t_s").at("data").size(), 2u);
}

TEST_F(FieldExport, H5dumpSeesTheShapesCompressionAndUnits) {
  store_fields();
  export_to(dir_ / "fields.h5");
  const std::string h5 = testreaders::sh_quoted(dir_ / "fields.h5");
  const auto header = testing::run_command("h5dump -p -H -d " + group("displacement", 0) + "/u_px " + h5);
  ASSERT_EQ(header.exit_code, 0) << header.output;
  EXPECT_NE(header.output.find("H5T_IEEE_F64LE"), std::string::npos) << header.output;
  EXPECT_NE(header.output.find("DATASPACE  SIMPLE { ( 3, 4 ) / ( 3, 4 ) }"), std::string::npos) << header.output;
  EXPECT_NE(header.output.find("COMPRESSION DEFLATE { LEVEL 4 }"), std::string::npos) << header.output;
  const auto units = testing::run_command("h5dump -a " + group("temperature", 1) + "/temperature_c/units " + h5);
  ASSERT_EQ(units.exit_code, 0) << units.output;
  EXPECT_NE(units.output.find("\"degC\""), std::string::npos) << units.output;
  const auto t = testing::run_command("h5dump -a " + group("temperature", 1) + "/t_s " + h5);
  EXPECT_NE(t.output.find("60.003"), std::string::npos) << t.output;
}

TEST_F(FieldExport, TheXdmfSidecarIsWellFormedAndPointsAtTheDatasets) {
  store_fields();
  export_to(dir_ / "fields.h5");
  const json xdmf = testreaders::xdmf_check(dir_ / "fields.xmf", dir_.path());
  const json h5 = testreaders::h5py_listing(dir_ / "fields.h5", dir_.path());
  ASSERT_EQ(xdmf.at("collections").size(), 2u);
  for (const char* kind : {"displacement", "temperature"}) {
    const json& grids = xdmf.at("collections").at(kind);
    ASSERT_EQ(grids.size(), 2u) << kind;
    for (int k = 0; k < 2; ++k) {
      const json& g = grids[k];
      const std::string frame_group = group(kind, k);
      EXPECT_EQ(g.at("name"), fmt::format("frame_{:06d}", frames_[1 + k].id));
      // Time as text, read back, equals the t_s attribute h5py reads: the same double.
      EXPECT_EQ(std::stod(g.at("time").get<std::string>()), h5.at(frame_group).at("attrs").at("t_s").get<double>());
      EXPECT_EQ(g.at("topology"), json::array({"2DRectMesh", "3 4"}));
      EXPECT_EQ(g.at("geometry_type"), "VXVY");
      ASSERT_EQ(g.at("geometry").size(), 2u);
      EXPECT_EQ(g.at("geometry")[0].at("ref"), "fields.h5:/grids/grid_000/x_mm") << "mm, relative file name";
      EXPECT_EQ(g.at("geometry")[0].at("shape"), json::array({kCols}));
      EXPECT_EQ(g.at("geometry")[1].at("shape"), json::array({kRows}));
      for (const auto& [name, item] : g.at("attributes").items()) {
        EXPECT_EQ(item.at("ref"), "fields.h5:" + frame_group + "/" + name);
        EXPECT_EQ(item.at("shape"), json::array({kRows, kCols})) << name << ": the dataset exists, of that shape";
        EXPECT_EQ(item.at("dims"), "3 4");
        EXPECT_EQ(item.at("format"), "HDF");
        const std::string dtype = h5.at(frame_group + "/" + name).at("dtype");
        EXPECT_EQ(item.at("type"), dtype == "uint8" ? "UChar" : "Float") << name;
        EXPECT_EQ(item.at("precision"), dtype == "uint8" ? "1" : "8") << name;
      }
    }
  }
  // u_px, v_px, valid, peak_ratio, sigma_u_px, sigma_v_px.
  EXPECT_EQ(xdmf.at("collections").at("displacement")[0].at("attributes").size(), 6u);
  EXPECT_TRUE(xdmf.at("collections").at("displacement")[0].at("attributes").contains("sigma_u_px"));
  EXPECT_TRUE(xdmf.at("collections").at("temperature")[0].at("attributes").contains("temperature_c"));
}

TEST_F(FieldExport, WithoutAScaleTheGridIsInPixels) {
  store_fields();
  export_to(dir_ / "px.h5", std::nullopt);
  const json h5 = testreaders::h5py_listing(dir_ / "px.h5", dir_.path());
  EXPECT_FALSE(h5.contains("/grids/grid_000/x_mm"));
  EXPECT_FALSE(h5.contains(group("displacement", 0) + "/x_mm"));
  EXPECT_FALSE(h5.at("/").at("attrs").contains("px_per_mm"));
  const json xdmf = testreaders::xdmf_check(dir_ / "px.xmf", dir_.path());
  EXPECT_EQ(xdmf.at("collections").at("displacement")[0].at("geometry")[1].at("ref"), "px.h5:/grids/grid_000/y_px");
}

// A processed run with the heater masked: the solve fills the heater's
// nodes (measured 0) and the export gives them as NaN, flag kept, beside
// the measured values exactly as stored.
TEST_F(FieldExport, AHeaterFilledInByTheSolveIsNaNAndFlaggedInTheHdf5) {
  cv::imwrite((run() / "holder.png").string(), testrun::holder_mask(truth_));
  pipeline::ProcessOptions process;
  process.overrides.mask = "holder.png";
  ASSERT_TRUE(pipeline::process_run(run(), process).complete);
  export_to(dir_ / "fields.h5");
  hdf5::File file(H5Fopen((dir_ / "fields.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  ASSERT_TRUE(file.valid());
  const storage::ProcessingStore results(run());
  int filled_under_holder = 0, invalid_vectors = 0;
  for (const auto& row : results.fields()) {
    const bool temperature = row.kind == "temperature";
    const auto stored = temperature ? pipeline::read_stored_field(run() / row.path, pipeline::kTemperatureColumns)
                                    : pipeline::read_stored_field(run() / row.path, pipeline::kDisplacementColumns);
    const std::string group = fmt::format("/{}/frame_{:06d}", row.kind, row.frame_id);
    const auto value = read_array(file.get(), group + (temperature ? "/temperature_c" : "/u_px"));
    const auto flag = read_array(file.get(), group + (temperature ? "/measured" : "/valid"), H5T_NATIVE_UINT8);
    const cv::Mat& stored_value = stored.column(temperature ? "temperature_c" : "u");
    const cv::Mat& stored_flag = stored.column(temperature ? "measured" : "valid");
    ASSERT_EQ(value.values.size(), stored_value.total());
    for (int r = 0; r < stored.rows(); ++r) {
      for (int c = 0; c < stored.cols(); ++c) {
        const std::size_t i = static_cast<std::size_t>(r * stored.cols() + c);
        const bool measured = stored_flag.at<double>(r, c) == 1;
        EXPECT_EQ(flag.values[i], measured ? 1 : 0) << group << " node " << i;
        if (measured) {
          const double v = stored_value.at<double>(r, c);
          if (std::isfinite(v)) EXPECT_EQ(value.values[i], v) << group << " node " << i;
          continue;
        }
        EXPECT_TRUE(std::isnan(value.values[i])) << group << " node " << i << " is not measured but has a value";
        const cv::Point node(static_cast<int>(stored.x_px[c]), static_cast<int>(stored.y_px[r]));
        if (temperature) {
          filled_under_holder += truth_.holder_px.contains(node) && std::isfinite(stored_value.at<double>(r, c));
        } else {
          ++invalid_vectors;
        }
      }
    }
  }
  EXPECT_GT(filled_under_holder, 20) << "the solve filled the heater in both frames: the case this test is about";
  EXPECT_GT(invalid_vectors, 20) << "the masked vectors";
}

TEST_F(FieldExport, ARunWithoutStoredFieldsSaysToProcessItFirst) {
  try {
    export_to(dir_ / "fields.h5");
    FAIL() << "exported nothing without an error";
  } catch (const NoStoredFields& e) {
    EXPECT_NE(std::string(e.what()).find("run `bosfuse process RUN --mode full` first"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "fields.h5"));
  EXPECT_FALSE(fs::exists(dir_ / "fields.xmf"));
}

// A broken second field stops the export after the first was written: the
// old files stay as they were and nothing partial is left beside them.
TEST_F(FieldExport, AFailedExportLeavesTheDestinationAsItWas) {
  store_fields();
  std::ofstream(run() / fmt::format("fields/frame_{:06d}_temperature.csv", frames_[2].id))
      << "x,y,temperature_c,measured,sigma_c\n8.0,8.0,hot,1,0.01\n";
  std::ofstream(dir_ / "fields.h5") << "the previous export";
  try {
    export_to(dir_ / "fields.h5");
    FAIL() << "a broken field was exported";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(fmt::format("stored temperature field of frame {}", frames_[2].id)), std::string::npos) << what;
    EXPECT_NE(what.find("'hot' is not a number"), std::string::npos) << what;
  }
  std::ifstream in(dir_ / "fields.h5");
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "the previous export");
  EXPECT_FALSE(fs::exists(dir_ / "fields.xmf"));
  for (const auto& entry : fs::directory_iterator(dir_.path())) {
    EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos) << entry.path();
  }
}

TEST_F(FieldExport, AStoredPathLeadingOutOfTheRunIsRefusedByName) {
  std::ofstream(dir_ / "outside.csv") << temperature_csv(0);
  {
    storage::ProcessingStore results(run(), true);
    results.add_field({0, frames_[1].id, "temperature", "../outside.csv", "{}"});
  }
  try {
    export_to(dir_ / "fields.h5");
    FAIL() << "a field outside the run was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("stored path '../outside.csv' refused"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "fields.h5"));
}

TEST_F(FieldExport, TheNameMustBeAnHdf5FileInAFolderThatExists) {
  store_fields();
  EXPECT_THROW(export_to(dir_ / "fields.xmf"), std::invalid_argument);
  EXPECT_THROW(export_to(dir_ / "fields.h5", 0.0), std::invalid_argument);
  try {
    export_to(dir_ / "no/such/fields.h5");
    FAIL() << "exported into a folder that does not exist";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no folder '" + (dir_ / "no/such").string() + "'"), std::string::npos)
        << e.what();
  }
}

// ---- the writer's own promises ---------------------------------------------

TEST(Hdf5Writer, ErrorsNameTheFileAndTheObjectAndPrintNothing) {
  testing::TempDir dir;
  const auto path = dir / "w.h5";
  ::testing::internal::CaptureStderr();
  std::string first, second;
  {
    hdf5::Writer out(path);
    out.create_group("/a");
    try {
      out.create_group("/a");
    } catch (const hdf5::Hdf5Error& e) {
      first = e.what();
    }
    try {
      const std::vector<double> values{1, 2, 3};
      out.write_2d("/missing/parent", values, 1, 3);
    } catch (const hdf5::Hdf5Error& e) {
      second = e.what();
    }
    out.close();
  }
  std::string third;
  try {
    hdf5::Writer out(dir / "no/such/dir/x.h5");
  } catch (const hdf5::Hdf5Error& e) {
    third = e.what();
  }
  const std::string printed = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(first.find("cannot create group '/a' in '" + path.string() + "'"), std::string::npos) << first;
  EXPECT_NE(second.find("cannot create dataset '/missing/parent' in '" + path.string() + "'"), std::string::npos)
      << second;
  EXPECT_NE(third.find("cannot create '" + (dir / "no/such/dir/x.h5").string() + "'"), std::string::npos) << third;
  EXPECT_EQ(printed, "") << "HDF5 printed its error stack itself";
  EXPECT_EQ(H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL), 0) << "every identifier was closed";
}

TEST(Hdf5Writer, AHandleClosesItsIdentifierOnce) {
  hdf5::Dataspace space(H5Screate(H5S_SCALAR));
  const hid_t id = space.get();
  EXPECT_GT(H5Iis_valid(id), 0);
  hdf5::Dataspace moved(std::move(space));
  EXPECT_FALSE(space.valid());
  EXPECT_TRUE(moved.close());
  EXPECT_FALSE(moved.valid());
  hdf5::QuietErrors quiet;
  EXPECT_LE(H5Iis_valid(id), 0);
}

}  // namespace
}  // namespace bosfuse::report
