#include "view/live_stream.h"

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>

#include "pipeline/quality_json.h"

namespace bosfuse::view {
namespace {

bool read_number(const char*& at, const char* end, std::int64_t& value) {
  const auto [next, ec] = std::from_chars(at, end, value);
  if (ec != std::errc() || value < 0) return false;
  at = next;
  return true;
}

}  // namespace

std::string format_cursor(const TailCursor& cursor) {
  return std::to_string(cursor.sample_rowid) + "-" + std::to_string(cursor.event_id) + "-" +
         std::to_string(cursor.frame_id);
}

std::optional<TailCursor> parse_cursor(const std::string& text) {
  TailCursor cursor;
  const char* at = text.data();
  const char* end = at + text.size();
  if (!read_number(at, end, cursor.sample_rowid) || at == end || *at++ != '-') return std::nullopt;
  if (!read_number(at, end, cursor.event_id) || at == end || *at++ != '-') return std::nullopt;
  if (!read_number(at, end, cursor.frame_id) || at != end) return std::nullopt;
  return cursor;
}

std::string sse_message(std::string_view type, std::string_view id, std::string_view data) {
  std::string message;
  message.reserve(type.size() + id.size() + data.size() + 24);
  message.append("event: ").append(type).append("\n");
  if (!id.empty()) message.append("id: ").append(id).append("\n");
  message.append("data: ").append(data).append("\n\n");
  return message;
}

LiveStream::LiveStream(const std::filesystem::path& run_dir, TailCursor from, const LiveBos* bos)
    : tail_(run_dir), cursor_(from), bos_(bos) {}

// Neither message carries an id: they restate the run, they are not records
// a reconnecting client could miss.
std::string LiveStream::clock_and_status(const RunSnapshot& snapshot) {
  std::string out;
  const storage::ExperimentClock& clock = snapshot.clock;
  const std::string clock_json = nlohmann::json{{"basis", clock.basis()},
                                                {"origin", clock.origin_name},
                                                {"origin_utc", storage::format_iso8601_utc(clock.origin_ns, 3)},
                                                {"time_scale", clock.time_scale},
                                                {"note", clock.note}}
                                     .dump();
  if (clock_json != sent_clock_) {
    out += sse_message("clock", "", clock_json);
    sent_clock_ = clock_json;
  }
  if (snapshot.status != sent_status_) {
    out += sse_message("status", "", nlohmann::json{{"status", snapshot.status}}.dump());
    sent_status_ = snapshot.status;
  }
  return out;
}

namespace {

nlohmann::json finite_or_null(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }

nlohmann::json bos_json(const LiveBosResult& r, const storage::ExperimentClock& clock, double camera_offset_s) {
  nlohmann::json probes = nlohmann::json::array();
  for (const auto& p : r.frame.probes) {
    nlohmann::json probe{{"channel", p.channel_id},      {"name", p.name},
                         {"x_px", p.position_px.x},      {"y_px", p.position_px.y},
                         {"u_px", finite_or_null(p.u_px)}, {"v_px", finite_or_null(p.v_px)},
                         {"shift_px", finite_or_null(p.shift_px)}, {"valid", p.valid}};
    if (p.temperature_c && std::isfinite(*p.temperature_c)) probe["t_c"] = *p.temperature_c;
    // Each σ only when estimated (as t_c): the page shows "± x °C" beside the temperature.
    for (const auto& [key, sigma] : {std::pair{"sigma_shift_px", p.sigma_shift_px},
                                     {"sigma_random_c", p.sigma_random_c},
                                     {"sigma_systematic_c", p.sigma_systematic_c}}) {
      if (sigma && std::isfinite(*sigma)) probe[key] = *sigma;
    }
    probes.push_back(std::move(probe));
  }
  return {{"frame_id", r.frame.frame.id},
          {"t_s", clock.seconds(r.frame.frame.t_ns) + camera_offset_s},
          {"width_px", r.frame.frame.width_px},
          {"height_px", r.frame.frame.height_px},
          {"probes", probes},
          {"quality", pipeline::to_json(r.frame.quality)},  // never NaN (fusion/image_quality.h)
          {"decode_ms", r.frame.decode_seconds * 1e3},
          {"evaluate_ms", r.frame.evaluate_seconds * 1e3},
          {"evaluated", r.evaluated},
          {"skipped", r.skipped}};
}

}  // namespace

std::string LiveStream::live_bos(const storage::ExperimentClock& clock) {
  std::string out;
  if (!bos_) return out;
  const LiveBosState state = bos_->state();
  const std::string state_json = nlohmann::json{{"state", state.state},
                                                {"temperature_source", state.temperature_source},
                                                {"evaluated", state.evaluated},
                                                {"skipped", state.skipped}}
                                     .dump();
  for (const LiveBosResult& r : bos_->results_from(bos_sent_)) {
    out += sse_message("bos", "", bos_json(r, clock, state.camera_offset_s).dump());
    ++bos_sent_;
  }
  if (state_json != sent_bos_state_) {
    out += sse_message("bos-state", "", state_json);
    sent_bos_state_ = state_json;
  }
  return out;
}

std::string LiveStream::next(const RunSnapshot& snapshot) {
  std::string out = clock_and_status(snapshot);
  const storage::ExperimentClock& clock = snapshot.clock;
  for (const storage::Event& event : tail_.events_after(cursor_.event_id, kRowsPerRead)) {
    cursor_.event_id = event.id;
    nlohmann::json data{{"t_s", clock.seconds(event.t_ns)}, {"kind", event.kind}, {"message", event.message}};
    if (event.device_id) {
      data["device_id"] = *event.device_id;
      const auto name = snapshot.device_names.find(*event.device_id);
      if (name != snapshot.device_names.end()) data["device"] = name->second;
    }
    out += sse_message("event", format_cursor(cursor_), data.dump());
  }
  for (const storage::TailSample& row : tail_.samples_after(cursor_.sample_rowid, kRowsPerRead)) {
    cursor_.sample_rowid = row.rowid;
    nlohmann::json data{{"t_s", clock.seconds(row.sample.t_ns)},
                        {"channel", row.sample.channel_id},
                        {"status", storage::to_string(row.sample.status)}};
    if (row.sample.value) data["value"] = *row.sample.value;
    out += sse_message("sample", format_cursor(cursor_), data.dump());
  }
  // Frames as counts: the page shows how many and when the last came.
  const auto frames = tail_.frames_after(cursor_.frame_id, kRowsPerRead);
  if (!frames.empty()) {
    cursor_.frame_id = frames.back().id;
    nlohmann::json data{{"count", tail_.frame_count_through(cursor_.frame_id)},
                        {"last_t_s", clock.seconds(frames.back().t_ns)},
                        {"width_px", frames.back().width_px},
                        {"height_px", frames.back().height_px}};
    // The first frame's time, for the rate over the run (read once per stream).
    if (!first_frame_t_ns_) first_frame_t_ns_ = tail_.frames_after(0, 1).front().t_ns;
    data["first_t_s"] = clock.seconds(*first_frame_t_ns_);
    // The camera that took the last one: the page shows frames in its device row.
    if (frames.back().device_id) data["device_id"] = *frames.back().device_id;
    out += sse_message("frames", format_cursor(cursor_), data.dump());
  }
  return out + live_bos(clock);
}

}  // namespace bosfuse::view
