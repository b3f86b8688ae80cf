#include "acquisition/cameras/exif_time.h"

#include <chrono>
#include <cstdio>
#include <string>

#include "acquisition/clock.h"

namespace bosfuse::acquisition {
namespace {

constexpr std::uint16_t kExifIfdPointer = 0x8769;
constexpr std::uint16_t kDateTimeOriginal = 0x9003;
constexpr std::uint16_t kDateTimeDigitized = 0x9004;
constexpr std::uint16_t kOffsetTimeOriginal = 0x9011;
constexpr std::uint16_t kSubSecTimeOriginal = 0x9291;
constexpr std::uint16_t kAsciiType = 2;

// A TIFF structure (the body of EXIF data) with its byte order; every read
// is bounds-checked, since the bytes come from whatever file was dropped in.
class TiffReader {
 public:
  explicit TiffReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}

  bool valid_header() {
    if (bytes_.size() < 8) return false;
    if (bytes_[0] == 'I' && bytes_[1] == 'I') {
      little_endian_ = true;
    } else if (bytes_[0] == 'M' && bytes_[1] == 'M') {
      little_endian_ = false;
    } else {
      return false;
    }
    return u16(2) == 42;
  }
  std::uint32_t first_ifd() const { return u32(4); }

  // The value of `tag` in the IFD at `ifd`: an offset-or-value word for
  // numbers, the text for ASCII entries.
  std::optional<std::uint32_t> number(std::uint32_t ifd, std::uint16_t tag) const {
    const auto entry = find(ifd, tag);
    if (!entry) return std::nullopt;
    return u32(*entry + 8);
  }
  std::optional<std::string> text(std::uint32_t ifd, std::uint16_t tag) const {
    const auto entry = find(ifd, tag);
    if (!entry || u16(*entry + 2) != kAsciiType) return std::nullopt;
    const std::uint32_t count = u32(*entry + 4);
    const std::size_t at = count <= 4 ? *entry + 8 : u32(*entry + 8);
    if (count == 0 || at + count > bytes_.size()) return std::nullopt;
    std::string value(reinterpret_cast<const char*>(bytes_.data() + at), count);
    while (!value.empty() && (value.back() == '\0' || value.back() == ' ')) value.pop_back();
    return value;
  }

 private:
  std::optional<std::size_t> find(std::uint32_t ifd, std::uint16_t tag) const {
    if (ifd + 2 > bytes_.size()) return std::nullopt;
    const std::uint16_t count = u16(ifd);
    for (std::uint16_t i = 0; i < count; ++i) {
      const std::size_t entry = ifd + 2 + 12u * i;
      if (entry + 12 > bytes_.size()) return std::nullopt;
      if (u16(entry) == tag) return entry;
    }
    return std::nullopt;
  }
  std::uint16_t u16(std::size_t at) const {
    if (at + 2 > bytes_.size()) return 0;
    return little_endian_ ? bytes_[at] | bytes_[at + 1] << 8 : bytes_[at] << 8 | bytes_[at + 1];
  }
  std::uint32_t u32(std::size_t at) const {
    if (at + 4 > bytes_.size()) return 0;
    const std::uint32_t low = u16(little_endian_ ? at : at + 2);
    const std::uint32_t high = u16(little_endian_ ? at + 2 : at);
    return high << 16 | low;
  }

  std::span<const std::uint8_t> bytes_;
  bool little_endian_ = true;
};

// The TIFF body of a JPEG's EXIF APP1 segment; the whole file for a TIFF.
std::span<const std::uint8_t> tiff_body(std::span<const std::uint8_t> file) {
  if (file.size() < 4 || file[0] != 0xFF || file[1] != 0xD8) return file;
  std::size_t at = 2;
  while (at + 4 <= file.size() && file[at] == 0xFF) {
    const std::uint8_t marker = file[at + 1];
    const std::size_t length = file[at + 2] << 8 | file[at + 3];
    if (marker == 0xDA || length < 2 || at + 2 + length > file.size()) break;  // start of scan: no more headers
    const auto segment = file.subspan(at + 4, length - 2);
    static constexpr std::uint8_t kExifHeader[] = {'E', 'x', 'i', 'f', 0, 0};
    if (marker == 0xE1 && segment.size() > 6 && std::equal(kExifHeader, kExifHeader + 6, segment.begin())) {
      return segment.subspan(6);
    }
    at += 2 + length;
  }
  return {};
}

std::optional<std::int64_t> parse_exif_datetime_ns(const std::string& text) {
  int year, month, day, hour, minute, second;
  if (std::sscanf(text.c_str(), "%4d:%2d:%2d %2d:%2d:%2d", &year, &month, &day, &hour, &minute, &second) != 6) {
    return std::nullopt;
  }
  const std::chrono::year_month_day date{std::chrono::year(year), std::chrono::month(month), std::chrono::day(day)};
  if (!plausible_year(year) || !date.ok() || hour > 23 || minute > 59 || second > 60) return std::nullopt;
  const auto t = std::chrono::sys_days(date) + std::chrono::hours(hour) + std::chrono::minutes(minute) +
                 std::chrono::seconds(second);
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

// "123" after the seconds means 0.123 s.
std::int64_t subsecond_ns(const std::string& digits) {
  std::int64_t ns = 0;
  std::int64_t place = 100'000'000;
  for (char c : digits) {
    if (c < '0' || c > '9' || place == 0) break;
    ns += (c - '0') * place;
    place /= 10;
  }
  return ns;
}

// "+01:00" -> 3600 s; the local time minus this is UTC.
std::optional<std::int64_t> zone_offset_s(const std::string& text) {
  int hours, minutes;
  char sign;
  if (std::sscanf(text.c_str(), "%c%2d:%2d", &sign, &hours, &minutes) != 3 || (sign != '+' && sign != '-') ||
      hours > 14 || minutes < 0 || minutes > 59) {
    return std::nullopt;  // no time zone is further than 14 h from UTC
  }
  return (sign == '-' ? -1 : 1) * (hours * 3600 + minutes * 60);
}

}  // namespace

std::optional<ExifCaptureTime> exif_capture_time(std::span<const std::uint8_t> file_bytes) {
  TiffReader tiff(tiff_body(file_bytes));
  if (!tiff.valid_header()) return std::nullopt;
  const auto exif_ifd = tiff.number(tiff.first_ifd(), kExifIfdPointer);
  if (!exif_ifd) return std::nullopt;
  auto datetime = tiff.text(*exif_ifd, kDateTimeOriginal);
  if (!datetime) datetime = tiff.text(*exif_ifd, kDateTimeDigitized);
  const auto t_ns = datetime ? parse_exif_datetime_ns(*datetime) : std::nullopt;
  if (!t_ns) return std::nullopt;
  ExifCaptureTime result{*t_ns + subsecond_ns(tiff.text(*exif_ifd, kSubSecTimeOriginal).value_or("")), false};
  if (const auto zone = tiff.text(*exif_ifd, kOffsetTimeOriginal)) {
    if (const auto offset_s = zone_offset_s(*zone)) {
      result.t_ns -= *offset_s * 1'000'000'000LL;
      result.had_zone_offset = true;
    }
  }
  return result;
}

}  // namespace bosfuse::acquisition
