#pragma once
// bosfuse.Run: a recorded run read-only (storage::RunStore::open_as_found):
// a run whose logger died is reported as interrupted and left as it is.
// Everything in experiment seconds (storage/experiment_clock.h), as every
// command shows it. run_binding.cc binds what was recorded (channels,
// samples, frames); run_results_binding.cc what `bosfuse process` stored
// beside it (fields, probe series, fits, agreements), read through a
// storage::ProcessingStore opened read-only on first use.

#include <pybind11/pybind11.h>

#include <filesystem>
#include <memory>

#include "storage/experiment_clock.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"

namespace bosfuse::python {

class Run {
 public:
  explicit Run(const std::filesystem::path& path);

  std::string status() const;
  pybind11::list channels() const;
  pybind11::list devices() const;
  pybind11::list events() const;
  pybind11::list frames() const;
  std::int64_t channel_id(const pybind11::object& channel) const;
  // (t_s, value, status): value NaN where status is not 0 (ok).
  pybind11::tuple samples(const pybind11::object& channel) const;

  const storage::RunStore& store() const { return store_; }
  const storage::ProcessingStore& results() const;
  const storage::ExperimentClock& clock() const { return clock_; }
  std::string path() const { return store_.dir().string(); }
  // The frame at index `i` of frames() (negative from the end); IndexError outside.
  storage::FrameRecord frame(long i) const;

 private:
  storage::RunStore store_;
  bool abandoned_;
  storage::ExperimentClock clock_;
  mutable std::unique_ptr<storage::ProcessingStore> results_;
};

// A types.SimpleNamespace of `fields`.
pybind11::object record(const pybind11::dict& fields);

void bind_run_results(pybind11::class_<Run>& run);

}  // namespace bosfuse::python
