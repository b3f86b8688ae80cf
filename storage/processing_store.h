#pragma once
// ProcessingStore reads and writes what `bosfuse process` and `bosfuse
// calibrate` derive from a run: BOS probe series at the thermocouples'
// image positions, Newton fits, agreement statistics, calibrations and the
// paths of field files (schema version 2, docs/SCHEMA.md). It opens its own
// connection to the run's `run.sqlite`, so it can be used beside a RunStore.
// Fits, agreements and calibrations are stored as JSON text (their
// structure belongs to fitting/ and fusion/, which storage does not know);
// fields as paths relative to the run folder.
//
// A store written before version 2 reads as having no results; opening it
// writable migrates it.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "storage/database.h"

namespace bosfuse::storage {

struct ProbeSeriesRecord {
  std::int64_t id = 0;
  std::optional<std::int64_t> channel_id;  // the thermocouple it sits on, if any
  std::string name;
  double x_px = 0;  // as requested (the evaluator may snap to a window centre)
  double y_px = 0;
};

struct ProbeSampleRecord {
  std::int64_t probe_id = 0;
  std::int64_t frame_id = 0;
  std::int64_t t_ns = 0;  // the frame's time
  double u_px = 0;
  double v_px = 0;
  double shift_px = 0;                  // |(u, v)|
  std::optional<double> temperature_c;  // when a calibration or the physical model gave one
  bool valid = false;
  // Standard uncertainties (k = 1) of this sample, nullopt where not
  // estimated: of the shift's components and magnitude (px), and of the
  // temperature, random (the vectors' noise through the conversion) and
  // systematic (the Type-B budget, GUM root sum of squares).
  std::optional<double> sigma_u_px;
  std::optional<double> sigma_v_px;
  std::optional<double> sigma_shift_px;
  std::optional<double> sigma_random_c;
  std::optional<double> sigma_systematic_c;
};

enum class FitSubject { kChannel, kProbe };

struct FitRecord {
  std::int64_t id = 0;
  FitSubject subject = FitSubject::kChannel;
  std::int64_t subject_id = 0;   // channel id or probe id
  std::int64_t origin_t_ns = 0;  // t = 0 of the fit
  bool ok = false;
  std::string json;
};

struct AgreementRecord {
  std::int64_t id = 0;
  std::int64_t channel_id = 0;
  std::int64_t probe_id = 0;
  std::string json;
};

struct CalibrationRecord {
  std::int64_t id = 0;
  std::int64_t created_ns = 0;
  std::string json;
};

// One `bosfuse process` of the run: the settings it used (JSON owned by
// pipeline/), its state and, when complete, a summary of what it found.
// `inherited` rows carry settings a replay copied from the recorded run.
struct ProcessingRecord {
  std::int64_t id = 0;
  std::int64_t started_ns = 0;
  std::optional<std::int64_t> finished_ns;
  // running, complete, abandoned, inherited. A processing that failed is
  // `abandoned` (nothing staged: nothing to resume) or still `running` (a
  // frame failed after others were staged: `--resume` continues at it), and
  // its summary_json then holds `failure`, the error in words.
  std::string status;
  std::string settings_json;
  std::string summary_json;
};

struct FieldRecord {
  std::int64_t id = 0;
  std::int64_t frame_id = 0;
  std::string kind;  // displacement, temperature
  std::string path;  // relative to the run folder
  std::string json;  // summary
};

class ProcessingStore {
 public:
  // Throws StorageError when the folder holds no run.
  explicit ProcessingStore(const std::filesystem::path& run_dir, bool writable = false);

  // Runs `work` in one transaction: all of it is stored or none.
  void in_transaction(const std::function<void()>& work);
  // Removes earlier probe series, samples, fits, agreements and field rows
  // (not calibrations, which are kept as a history).
  void clear_results();

  std::int64_t add_probe(const ProbeSeriesRecord& probe);
  void write_probe_samples(std::span<const ProbeSampleRecord> samples);
  std::int64_t add_fit(const FitRecord& fit);
  std::int64_t add_agreement(const AgreementRecord& agreement);
  std::int64_t add_calibration(const CalibrationRecord& calibration);
  std::int64_t add_field(const FieldRecord& field);

  // Processings (schema version 4). The results above are the current
  // ones; a processing writes its own aside ("staged") and replaces them
  // only when it completes, in one transaction.
  std::int64_t begin_processing(const std::string& settings_json, std::int64_t started_ns);
  // A running processing's settings, completed with what its first frame
  // found (the scene's search bound); other processings are left alone.
  void update_running_settings(std::int64_t processing_id, const std::string& settings_json);
  std::int64_t add_inherited_settings(const std::string& settings_json, std::int64_t created_ns);
  std::optional<ProcessingRecord> current_processing() const;  // the newest complete one
  std::optional<ProcessingRecord> latest_settings() const;     // the newest complete or inherited one
  std::optional<ProcessingRecord> unfinished_processing() const;  // the newest still `running`
  // The newest processing of any status but inherited: what the last
  // `process` did, complete, running, failed or discarded.
  std::optional<ProcessingRecord> latest_processing() const;
  // Drops what `processing_id` staged and marks it abandoned.
  void abandon_processing(std::int64_t processing_id);
  // A processing that failed, with `summary_json` saying why. One that had
  // staged no frame has nothing to resume: it is abandoned (no `running` row
  // stays); one that had stays `running`, resumable at the failing frame.
  void fail_processing(std::int64_t processing_id, const std::string& summary_json, std::int64_t finished_ns);
  // A staged probe series; an existing one of that name is returned as is (resume).
  std::int64_t stage_probe(std::int64_t processing_id, const ProbeSeriesRecord& probe);
  std::vector<ProbeSeriesRecord> staged_probes(std::int64_t processing_id) const;
  std::vector<ProbeSampleRecord> staged_probe_samples(std::int64_t probe_id) const;  // in time order
  std::vector<FieldRecord> staged_fields(std::int64_t processing_id) const;
  // One frame's results, in one transaction: after a crash a frame is
  // either wholly staged or not at all.
  void stage_frame(std::int64_t processing_id, std::int64_t frame_id, const std::string& json,
                   std::span<const ProbeSampleRecord> samples, std::span<const FieldRecord> fields);
  std::vector<std::int64_t> staged_frame_ids(std::int64_t processing_id) const;
  // Each staged frame's id and the summary it was staged with, in frame order.
  std::vector<std::pair<std::int64_t, std::string>> staged_frame_summaries(std::int64_t processing_id) const;
  // Replaces the current results by what `processing_id` staged plus these
  // fits and agreements (their probe ids are the staged ones, which are
  // kept), and marks it complete; all in one transaction.
  void complete_processing(std::int64_t processing_id, std::span<const FitRecord> fits,
                           std::span<const AgreementRecord> agreements, const std::string& summary_json,
                           std::int64_t finished_ns);

  std::vector<ProbeSeriesRecord> probes() const;
  std::vector<ProbeSampleRecord> probe_samples(std::int64_t probe_id) const;  // in time order
  std::vector<FitRecord> fits() const;
  std::vector<AgreementRecord> agreements() const;
  std::optional<CalibrationRecord> latest_calibration() const;
  std::vector<FieldRecord> fields() const;

 private:
  bool has_results_tables() const { return version_ >= 2; }
  bool has_processings() const { return version_ >= 4; }
  bool has_sample_sigmas() const { return version_ >= 5; }
  std::optional<ProcessingRecord> processing_where(const char* condition) const;

  mutable Database db_;
  std::int64_t run_id_ = 0;
  int version_ = 0;
};

}  // namespace bosfuse::storage
