#include "app/progress_display.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/ioctl.h>
#include <unistd.h>

namespace bosfuse::app {
namespace {

// The standard streams are the only ones with a file descriptor to ask.
int file_descriptor_of(const std::ostream& out) {
  if (&out == &std::cerr || &out == &std::clog) return STDERR_FILENO;
  if (&out == &std::cout) return STDOUT_FILENO;
  return -1;
}

std::size_t terminal_columns(int fd) {
  winsize size{};
  if (fd >= 0 && ioctl(fd, TIOCGWINSZ, &size) == 0 && size.ws_col > 0) return size.ws_col;
  return 80;
}

// A control character in `what` would move the cursor and break the line.
std::string printable(std::string_view text) {
  std::string clean(text);
  for (char& c : clean) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  }
  return clean;
}

// Cut to `columns` characters (UTF-8 code points, so "—" is not split): a
// line that wraps cannot be rewritten with a carriage return.
std::string fit_to(std::string text, std::size_t columns) {
  std::size_t characters = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if ((static_cast<unsigned char>(text[i]) & 0xC0) == 0x80) continue;  // a continuation byte
    if (++characters > columns) {
      text.resize(i);
      break;
    }
  }
  return text;
}

std::string_view without_trailing_newlines(std::string_view line) {
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.remove_suffix(1);
  return line;
}

}  // namespace

std::string format_clock_duration(std::chrono::nanoseconds duration) {
  const auto seconds = std::max<std::int64_t>(
      0, std::chrono::duration_cast<std::chrono::seconds>(duration + std::chrono::milliseconds(500)).count());
  if (seconds < 3600) return fmt::format("{}:{:02}", seconds / 60, seconds % 60);
  return fmt::format("{}:{:02}:{:02}", seconds / 3600, seconds / 60 % 60, seconds % 60);
}

ProgressDisplay::ProgressDisplay(std::ostream& out)
    : ProgressDisplay(out, isatty(file_descriptor_of(out)) == 1, [] { return std::chrono::steady_clock::now(); }) {
  columns_ = terminal_columns(file_descriptor_of(out));
  silent_ = !spdlog::should_log(spdlog::level::info);
}

ProgressDisplay::ProgressDisplay(std::ostream& out, bool terminal, Clock clock)
    : out_(out), terminal_(terminal), clock_(std::move(clock)), next_phase_origin_(clock_()) {}

ProgressDisplay::~ProgressDisplay() { finish(); }

void ProgressDisplay::step(std::size_t done, std::size_t total, std::string_view what) {
  const std::lock_guard lock(mutex_);
  const auto now = clock_();
  if (!stepped_ || total != total_ || done < done_) {
    phase_start_ = now;
    phase_start_done_ = done;
    phase_origin_ = next_phase_origin_.value_or(now);
    next_phase_origin_.reset();
  }
  stepped_ = true;
  last_time_ = now;
  done_ = done;
  total_ = total;
  what_ = printable(what);
  draw_locked();
}

void ProgressDisplay::note(std::string_view line) {
  const std::lock_guard lock(mutex_);
  // A note between phases announces the next one's work ("processing
  // ..."): its time is when that phase's elapsed time starts, so time spent
  // before it (a recording) is not counted in it.
  if (!(stepped_ && (total_ == 0 || done_ < total_))) next_phase_origin_ = clock_();
  if (silent_) return;
  if (drawn_) out_ << "\r\x1b[K";
  out_ << without_trailing_newlines(line) << "\n";
  drawn_ = false;
  if (terminal_ && stepped_) {
    draw_locked();
  } else {
    out_.flush();
  }
}

void ProgressDisplay::finish() {
  const std::lock_guard lock(mutex_);
  if (drawn_) out_ << "\n";
  drawn_ = false;
  out_.flush();
}

std::optional<std::chrono::nanoseconds> ProgressDisplay::eta() const {
  const std::lock_guard lock(mutex_);
  return eta_locked();
}

std::optional<std::chrono::nanoseconds> ProgressDisplay::eta_locked() const {
  if (!stepped_) return std::nullopt;
  if (done_ >= total_) return std::chrono::nanoseconds(0);
  const auto spent = last_time_ - phase_start_;
  if (done_ <= phase_start_done_ || spent <= std::chrono::nanoseconds(0)) return std::nullopt;
  const double per_item_ns =
      static_cast<double>(std::chrono::nanoseconds(spent).count()) / static_cast<double>(done_ - phase_start_done_);
  return std::chrono::nanoseconds(static_cast<std::int64_t>(per_item_ns * static_cast<double>(total_ - done_)));
}

// Counts first, so they keep their columns while `what` changes and a
// narrow terminal cuts only `what`.
std::string ProgressDisplay::line_locked() const {
  const std::string elapsed = format_clock_duration(last_time_ - phase_origin_);
  std::string line;
  if (total_ == 0) {
    line = fmt::format("{}  {} elapsed", done_, elapsed);
  } else {
    const auto eta = eta_locked();
    line = fmt::format("{}/{} {:>3}%  {} elapsed  ETA {}", done_, total_, std::min(done_, total_) * 100 / total_,
                       elapsed, eta ? format_clock_duration(*eta) : "—");
  }
  if (!what_.empty()) line += "  " + what_;
  return line;
}

void ProgressDisplay::draw_locked() {
  if (silent_) return;
  if (terminal_) {
    // One column spare: some terminals wrap as soon as the last one is written.
    out_ << "\r" << fit_to(line_locked(), columns_ > 1 ? columns_ - 1 : columns_) << "\x1b[K";
    drawn_ = true;
  } else {
    out_ << line_locked() << "\n";
  }
  out_.flush();
}

}  // namespace bosfuse::app
