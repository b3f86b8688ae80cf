#pragma once
// Writing an HDF5 file through HDF5's C API (Debian libhdf5, 1.10) with every
// identifier owned and every failure an exception. Use it for files other
// programs read (h5py, MATLAB h5read, ParaView): the report's field export
// (field_export.h) is built on it.
//
// An `hid_t` is an integer, not a pointer, so it cannot sit in a unique_ptr;
// Handle<Close> is the same idea for it, and the close function is part of
// the type, so a dataset can never be closed with H5Gclose. While a Writer
// exists, HDF5's own printing of its error stack to stderr is off; a failure
// becomes an Hdf5Error naming the file, the object and what HDF5 said.

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace bosfuse::report::hdf5 {

// An HDF5 identifier closed with `Close` when the owner goes. The destructor
// ignores a failing close (destructors never throw): call close() where the
// outcome matters, e.g. a file's close, which writes what HDF5 buffered.
template <herr_t (*Close)(hid_t)>
class Handle {
 public:
  Handle() = default;
  explicit Handle(hid_t id) : id_(id) {}
  ~Handle() { close(); }
  Handle(Handle&& other) noexcept : id_(std::exchange(other.id_, H5I_INVALID_HID)) {}
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      close();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // Closes now; false when HDF5 reports a failure (the id is released either way).
  bool close() noexcept {
    if (id_ < 0) return true;
    const herr_t status = Close(std::exchange(id_, H5I_INVALID_HID));
    return status >= 0;
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
};

using File = Handle<H5Fclose>;
using Group = Handle<H5Gclose>;
using Dataset = Handle<H5Dclose>;
using Dataspace = Handle<H5Sclose>;
using Attribute = Handle<H5Aclose>;
using Datatype = Handle<H5Tclose>;
using PropertyList = Handle<H5Pclose>;

class Hdf5Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Turns HDF5's automatic error printing off for its lifetime and restores
// what was set before. HDF5 keeps this per process: nest, never interleave.
class QuietErrors {
 public:
  QuietErrors();
  ~QuietErrors();
  QuietErrors(const QuietErrors&) = delete;
  QuietErrors& operator=(const QuietErrors&) = delete;

 private:
  H5E_auto2_t previous_ = nullptr;
  void* previous_data_ = nullptr;
};

// What HDF5's error stack says now, outermost call first ("unable to create
// file; unable to open file: name = ..., errno = 13, ..."), then cleared.
std::string take_error_stack();

// One file being written. Object paths are absolute ("/displacement/frame_000012/u_px");
// a parent group must have been created first.
class Writer {
 public:
  // Creates `path`, replacing a file of that name. Messages name the file
  // `shown_as` when given (the destination of a file written under a
  // temporary name).
  explicit Writer(std::filesystem::path path, std::filesystem::path shown_as = {});

  void create_group(const std::string& path);
  // A row-major rows × cols array (HDF5 shape [rows, cols]), gzip level 4
  // with the shuffle filter, in chunks of at most 128 × 128.
  void write_2d(const std::string& path, std::span<const double> data, std::size_t rows, std::size_t cols);
  void write_2d(const std::string& path, std::span<const std::uint8_t> data, std::size_t rows, std::size_t cols);
  void write_1d(const std::string& path, std::span<const double> data);
  void write_1d(const std::string& path, std::span<const std::int64_t> data);
  // Variable-length UTF-8 strings, which h5py reads as bytes (.asstr() for str).
  void write_1d(const std::string& path, std::span<const std::string> data);
  // A frames × rows × cols array filled one frame at a time (write_frame), so
  // a sequence never holds more than one frame's field: chunks of one frame
  // by at most 128 × 128, compressed as write_2d's. A frame never written
  // reads as `fill`.
  void create_frames(const std::string& path, std::size_t frames, std::size_t rows, std::size_t cols, double fill);
  void create_frames(const std::string& path, std::size_t frames, std::size_t rows, std::size_t cols,
                     std::uint8_t fill);
  // Frame `frame` of an array create_frames() made: rows × cols values, row-major.
  void write_frame(const std::string& path, std::size_t frame, std::span<const double> data);
  void write_frame(const std::string& path, std::size_t frame, std::span<const std::uint8_t> data);
  // `object` is a group or dataset path ("/" for the file). Strings are
  // variable-length UTF-8, which h5py reads as str and MATLAB as char.
  void set_attribute(const std::string& object, const std::string& name, std::string_view value);
  void set_attribute(const std::string& object, const std::string& name, double value);
  void set_attribute(const std::string& object, const std::string& name, std::int64_t value);
  // `link` names the object at `target` too (an HDF5 soft link; h5py and h5read follow it).
  void link(const std::string& target, const std::string& link);

  // Writes what HDF5 still buffers and closes the file; throws if that
  // fails. Without it the destructor closes the file and ignores the outcome.
  void close();

  const std::filesystem::path& path() const { return path_; }

 private:
  [[noreturn]] void fail(std::string_view action, std::string_view object) const;
  void write(const std::string& path, hid_t file_type, hid_t memory_type, const void* data,
             std::span<const hsize_t> dims, bool compress);
  void create_frames(const std::string& path, hid_t file_type, hid_t memory_type, const void* fill,
                     std::span<const hsize_t, 3> dims);
  void write_frame(const std::string& path, hid_t memory_type, std::size_t frame, const void* data, std::size_t size);
  void attribute(const std::string& object, const std::string& name, hid_t file_type, hid_t memory_type,
                 const void* value);

  std::filesystem::path path_;
  std::filesystem::path shown_as_;
  QuietErrors quiet_;  // before file_: errors are quiet until the file is closed
  File file_;
};

}  // namespace bosfuse::report::hdf5
