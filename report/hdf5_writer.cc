#include "report/hdf5_writer.h"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

namespace bosfuse::report::hdf5 {

QuietErrors::QuietErrors() {
  H5Eget_auto2(H5E_DEFAULT, &previous_, &previous_data_);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

QuietErrors::~QuietErrors() { H5Eset_auto2(H5E_DEFAULT, previous_, previous_data_); }

std::string take_error_stack() {
  std::vector<std::string> messages;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_DOWNWARD,
      [](unsigned, const H5E_error2_t* error, void* data) -> herr_t {
        auto& out = *static_cast<std::vector<std::string>*>(data);
        std::string text = error->desc ? error->desc : "";
        std::replace(text.begin(), text.end(), '\n', ' ');  // the open error quotes ctime(), newline included
        if (!text.empty() && std::find(out.begin(), out.end(), text) == out.end()) out.push_back(text);
        return 0;
      },
      &messages);
  H5Eclear2(H5E_DEFAULT);
  std::string joined;
  for (const auto& m : messages) joined += (joined.empty() ? "" : "; ") + m;
  return joined.empty() ? "HDF5 gave no reason" : joined;
}

Writer::Writer(std::filesystem::path path, std::filesystem::path shown_as)
    : path_(std::move(path)), shown_as_(shown_as.empty() ? path_ : std::move(shown_as)) {
  file_ = File(H5Fcreate(path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  if (!file_.valid()) fail("cannot create", "");
}

void Writer::fail(std::string_view action, std::string_view object) const {
  const std::string reason = take_error_stack();
  if (object.empty()) throw Hdf5Error(fmt::format("{} '{}': {}", action, shown_as_.string(), reason));
  throw Hdf5Error(fmt::format("{} '{}' in '{}': {}", action, object, shown_as_.string(), reason));
}

void Writer::create_group(const std::string& path) {
  Group group(H5Gcreate2(file_.get(), path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!group.valid()) fail("cannot create group", path);
}

void Writer::write(const std::string& path, hid_t file_type, hid_t memory_type, const void* data,
                   std::span<const hsize_t> dims, bool compress) {
  Dataspace space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr));
  if (!space.valid()) fail("cannot describe the shape of", path);
  PropertyList create(H5Pcreate(H5P_DATASET_CREATE));
  if (!create.valid()) fail("cannot set up", path);
  const bool empty = std::any_of(dims.begin(), dims.end(), [](hsize_t d) { return d == 0; });
  if (compress && !empty) {
    // Fields are small next to a chunk's overhead up to ~128 nodes a side; larger
    // (per-pixel) fields are split so a reader taking a window reads few chunks.
    std::vector<hsize_t> chunk(dims.begin(), dims.end());
    for (auto& c : chunk) c = std::min<hsize_t>(c, 128);
    if (H5Pset_chunk(create.get(), static_cast<int>(chunk.size()), chunk.data()) < 0 ||
        H5Pset_shuffle(create.get()) < 0 || H5Pset_deflate(create.get(), 4) < 0) {
      fail("cannot set chunks and compression of", path);
    }
  }
  Dataset dataset(
      H5Dcreate2(file_.get(), path.c_str(), file_type, space.get(), H5P_DEFAULT, create.get(), H5P_DEFAULT));
  if (!dataset.valid()) fail("cannot create dataset", path);
  if (!empty && H5Dwrite(dataset.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    fail("cannot write dataset", path);
  }
  if (!dataset.close()) fail("cannot close dataset", path);
}

namespace {
void check_size(std::size_t size, std::size_t rows, std::size_t cols, const std::string& path) {
  if (size != rows * cols) {
    throw std::invalid_argument(fmt::format("'{}': {} values for a {} × {} array", path, size, rows, cols));
  }
}
}  // namespace

void Writer::write_2d(const std::string& path, std::span<const double> data, std::size_t rows, std::size_t cols) {
  check_size(data.size(), rows, cols, path);
  const hsize_t dims[] = {rows, cols};
  write(path, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, data.data(), dims, true);
}

void Writer::write_2d(const std::string& path, std::span<const std::uint8_t> data, std::size_t rows, std::size_t cols) {
  check_size(data.size(), rows, cols, path);
  const hsize_t dims[] = {rows, cols};
  write(path, H5T_STD_U8LE, H5T_NATIVE_UINT8, data.data(), dims, true);
}

void Writer::write_1d(const std::string& path, std::span<const double> data) {
  const hsize_t dims[] = {data.size()};
  write(path, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, data.data(), dims, false);
}

void Writer::write_1d(const std::string& path, std::span<const std::int64_t> data) {
  const hsize_t dims[] = {data.size()};
  write(path, H5T_STD_I64LE, H5T_NATIVE_INT64, data.data(), dims, false);
}

void Writer::write_1d(const std::string& path, std::span<const std::string> data) {
  Datatype type(H5Tcopy(H5T_C_S1));
  if (!type.valid() || H5Tset_size(type.get(), H5T_VARIABLE) < 0 || H5Tset_cset(type.get(), H5T_CSET_UTF8) < 0) {
    fail("cannot make a string type for", path);
  }
  std::vector<const char*> pointers;
  pointers.reserve(data.size());
  for (const auto& text : data) pointers.push_back(text.c_str());
  const hsize_t dims[] = {data.size()};
  write(path, type.get(), type.get(), pointers.data(), dims, false);
}

void Writer::create_frames(const std::string& path, hid_t file_type, hid_t memory_type, const void* fill,
                           std::span<const hsize_t, 3> dims) {
  if (dims[0] == 0 || dims[1] == 0 || dims[2] == 0) {
    throw std::invalid_argument(
        fmt::format("'{}': a {} × {} × {} array has no values", path, dims[0], dims[1], dims[2]));
  }
  Dataspace space(H5Screate_simple(3, dims.data(), nullptr));
  if (!space.valid()) fail("cannot describe the shape of", path);
  PropertyList create(H5Pcreate(H5P_DATASET_CREATE));
  if (!create.valid()) fail("cannot set up", path);
  const hsize_t chunk[] = {1, std::min<hsize_t>(dims[1], 128), std::min<hsize_t>(dims[2], 128)};
  if (H5Pset_chunk(create.get(), 3, chunk) < 0 || H5Pset_shuffle(create.get()) < 0 ||
      H5Pset_deflate(create.get(), 4) < 0 || H5Pset_fill_value(create.get(), memory_type, fill) < 0 ||
      H5Pset_fill_time(create.get(), H5D_FILL_TIME_ALLOC) < 0) {
    fail("cannot set chunks, compression and fill value of", path);
  }
  Dataset dataset(
      H5Dcreate2(file_.get(), path.c_str(), file_type, space.get(), H5P_DEFAULT, create.get(), H5P_DEFAULT));
  if (!dataset.valid()) fail("cannot create dataset", path);
  if (!dataset.close()) fail("cannot close dataset", path);
}

void Writer::create_frames(const std::string& path, std::size_t frames, std::size_t rows, std::size_t cols,
                           double fill) {
  const hsize_t dims[] = {frames, rows, cols};
  create_frames(path, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &fill, std::span<const hsize_t, 3>(dims));
}

void Writer::create_frames(const std::string& path, std::size_t frames, std::size_t rows, std::size_t cols,
                           std::uint8_t fill) {
  const hsize_t dims[] = {frames, rows, cols};
  create_frames(path, H5T_STD_U8LE, H5T_NATIVE_UINT8, &fill, std::span<const hsize_t, 3>(dims));
}

void Writer::write_frame(const std::string& path, hid_t memory_type, std::size_t frame, const void* data,
                         std::size_t size) {
  Dataset dataset(H5Dopen2(file_.get(), path.c_str(), H5P_DEFAULT));
  if (!dataset.valid()) fail("cannot open dataset", path);
  Dataspace space(H5Dget_space(dataset.get()));
  hsize_t dims[3] = {0, 0, 0};
  if (!space.valid() || H5Sget_simple_extent_ndims(space.get()) != 3 ||
      H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0) {
    fail("cannot read the shape of", path);
  }
  if (frame >= dims[0] || size != dims[1] * dims[2]) {
    throw std::invalid_argument(fmt::format("'{}': frame {} of {} values for a {} × {} × {} array", path, frame, size,
                                            dims[0], dims[1], dims[2]));
  }
  const hsize_t start[] = {frame, 0, 0};
  const hsize_t count[] = {1, dims[1], dims[2]};
  Dataspace memory(H5Screate_simple(3, count, nullptr));
  if (!memory.valid() || H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr) < 0) {
    fail("cannot select a frame of", path);
  }
  if (H5Dwrite(dataset.get(), memory_type, memory.get(), space.get(), H5P_DEFAULT, data) < 0) {
    fail(fmt::format("cannot write frame {} of dataset", frame), path);
  }
  if (!dataset.close()) fail("cannot close dataset", path);
}

void Writer::write_frame(const std::string& path, std::size_t frame, std::span<const double> data) {
  write_frame(path, H5T_NATIVE_DOUBLE, frame, data.data(), data.size());
}

void Writer::write_frame(const std::string& path, std::size_t frame, std::span<const std::uint8_t> data) {
  write_frame(path, H5T_NATIVE_UINT8, frame, data.data(), data.size());
}

void Writer::attribute(const std::string& object, const std::string& name, hid_t file_type, hid_t memory_type,
                       const void* value) {
  const std::string what = object + (object.ends_with('/') ? "" : "/") + "@" + name;
  Dataspace scalar(H5Screate(H5S_SCALAR));
  if (!scalar.valid()) fail("cannot describe attribute", what);
  Attribute attribute(H5Acreate_by_name(file_.get(), object.c_str(), name.c_str(), file_type, scalar.get(), H5P_DEFAULT,
                                        H5P_DEFAULT, H5P_DEFAULT));
  if (!attribute.valid()) fail("cannot create attribute", what);
  if (H5Awrite(attribute.get(), memory_type, value) < 0) fail("cannot write attribute", what);
}

void Writer::set_attribute(const std::string& object, const std::string& name, std::string_view value) {
  Datatype type(H5Tcopy(H5T_C_S1));
  if (!type.valid() || H5Tset_size(type.get(), H5T_VARIABLE) < 0 || H5Tset_cset(type.get(), H5T_CSET_UTF8) < 0) {
    fail("cannot make a string type for attribute", object + "@" + name);
  }
  const std::string text(value);  // NUL-terminated, as HDF5 wants a variable-length string
  const char* pointer = text.c_str();
  attribute(object, name, type.get(), type.get(), &pointer);
}

void Writer::set_attribute(const std::string& object, const std::string& name, double value) {
  attribute(object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value);
}

void Writer::set_attribute(const std::string& object, const std::string& name, std::int64_t value) {
  attribute(object, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &value);
}

void Writer::link(const std::string& target, const std::string& link) {
  if (H5Lcreate_soft(target.c_str(), file_.get(), link.c_str(), H5P_DEFAULT, H5P_DEFAULT) < 0) {
    fail("cannot create link", link + " -> " + target);
  }
}

void Writer::close() {
  if (H5Fflush(file_.get(), H5F_SCOPE_GLOBAL) < 0) fail("cannot write", "");
  if (!file_.close()) fail("cannot close", "");
}

}  // namespace bosfuse::report::hdf5
