// HID and USB-TC-32 reports. The first bytes choose a HID channel (one of the
// built-in profiles, MCC USB-TC inputs 0-7 and cold junctions or TEMPer, or
// a generic channel with a fuzzed report id, value offset, type, byte
// order, scale, offset, open-circuit codes and valid range that Validate()
// accepts), the rest is the reply report a device sends. The reply is
// decoded by HidChannel::decode, by decode_hid_value at every offset and
// type, by HidProtocol::apply_burnout as a burnout bitmap, and (its first
// bytes) by decode_tc32_reading as a USB-TC-32 vendor reply.
// Invariants: statuses are valid SampleStatus values; a value is present
// exactly when the status is kOk, and is finite and inside the valid range;
// a reply shorter than reply_size() or from another report id is kBadReply;
// decode_hid_value answers exactly when offset + width fits the reply;
// apply_burnout only turns readings of channels with a burnout bit into
// open-circuit or bad-reply, never into kOk; a USB-TC-32 reply of any length
// but 4 is kBadReply and a 4-byte one is kOk exactly when its float is
// finite and none of the -777/-888/-999 sentinels.

#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "acquisition/drivers/hid_protocol.h"
#include "acquisition/drivers/usb_tc32_protocol.h"
#include "fuzz/fuzz_support.h"

using namespace bosfuse::acquisition;
using bosfuse::storage::SampleStatus;

namespace {

HidChannel make_channel(FuzzedDataProvider& in) {
  switch (in.ConsumeIntegralInRange<int>(0, 3)) {
    case 0:
      return mcc_usb_tc_channel(in.ConsumeIntegralInRange<int>(0, 7));
    case 1:
      return mcc_usb_tc_channel(kMccColdJunction0 + in.ConsumeIntegralInRange<int>(0, 1));
    case 2:
      return temper_channel(in.ConsumeBool() ? 256.0 : 100.0);
    default:
      break;
  }
  HidChannel c;
  c.name = "generic";
  c.request = {in.ConsumeIntegral<std::uint8_t>()};
  if (in.ConsumeBool()) c.reply_report_id = in.ConsumeIntegral<std::uint8_t>();
  c.value_offset = in.ConsumeIntegralInRange<int>(-2, 70);  // Validate() rejects those outside 0..63
  c.type = static_cast<HidValueType>(in.ConsumeIntegralInRange<int>(0, 4));
  c.big_endian = in.ConsumeBool();
  c.scale = (in.ConsumeBool() ? 1 : -1) * in.ConsumeFloatingPointInRange<double>(1e-6, 1e6);
  c.offset = in.ConsumeFloatingPointInRange<double>(-1e6, 1e6);
  if (in.ConsumeBool()) c.open_circuit_codes.push_back(in.ConsumeIntegral<std::int16_t>());
  if (in.ConsumeBool()) c.valid_min = in.ConsumeFloatingPointInRange<double>(-1e9, 1e9);
  if (in.ConsumeBool()) c.valid_max = in.ConsumeFloatingPointInRange<double>(-1e9, 1e9);
  c.burnout_bit = in.ConsumeIntegralInRange<int>(-1, 7);
  return c;
}

void check_status(const ChannelReading& r) {
  const int status = static_cast<int>(r.status);
  FUZZ_CHECK(status >= 0 && status < bosfuse::storage::kSampleStatusCount);
  FUZZ_CHECK(r.value.has_value() == (r.status == SampleStatus::kOk));
  if (r.value) FUZZ_CHECK(std::isfinite(*r.value));
}

int width(HidValueType type) { return type == HidValueType::kInt16 || type == HidValueType::kUint16 ? 2 : 4; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  HidProtocol protocol;
  for (int n = in.ConsumeIntegralInRange<int>(1, 4); n > 0; --n) {
    HidChannel c = make_channel(in);
    if (c.Validate().empty()) protocol.channels.push_back(std::move(c));
  }
  if (in.ConsumeBool()) protocol.burnout_reply_report_id = in.ConsumeIntegral<std::uint8_t>();
  const std::vector<std::uint8_t> burnout = in.ConsumeBytes<std::uint8_t>(in.ConsumeIntegralInRange<int>(0, 3));
  const std::vector<std::uint8_t> reply = in.ConsumeRemainingBytes<std::uint8_t>();
  const std::span<const std::uint8_t> bytes(reply);

  std::vector<ChannelReading> readings;
  for (const HidChannel& c : protocol.channels) {
    const ChannelReading r = c.decode(bytes);
    check_status(r);
    if (reply.size() < c.reply_size()) FUZZ_CHECK(r.status == SampleStatus::kBadReply);
    if (c.reply_report_id && (reply.empty() || reply[0] != *c.reply_report_id)) {
      FUZZ_CHECK(r.status == SampleStatus::kBadReply);
    }
    if (r.value) {
      if (c.valid_min) FUZZ_CHECK(*r.value >= *c.valid_min);
      if (c.valid_max) FUZZ_CHECK(*r.value <= *c.valid_max);
    }
    readings.push_back(r);
  }

  const std::vector<ChannelReading> before = readings;
  protocol.apply_burnout(burnout, readings);
  for (std::size_t i = 0; i < readings.size(); ++i) {
    check_status(readings[i]);
    if (protocol.channels[i].burnout_bit < 0) {
      FUZZ_CHECK(readings[i].status == before[i].status);
    } else if (readings[i].status != before[i].status) {
      FUZZ_CHECK(readings[i].status == SampleStatus::kOpenCircuit || readings[i].status == SampleStatus::kBadReply);
    }
  }

  for (int offset = -1; offset <= static_cast<int>(reply.size()) && offset < 72; ++offset) {
    for (int type = 0; type <= 4; ++type) {
      for (bool big : {false, true}) {
        const auto v = decode_hid_value(bytes, offset, static_cast<HidValueType>(type), big);
        const bool fits = offset >= 0 && static_cast<std::size_t>(offset + width(static_cast<HidValueType>(type))) <= reply.size();
        FUZZ_CHECK(v.has_value() == fits);
      }
    }
  }

  const ChannelReading tc32 = decode_tc32_reading(bytes.first(std::min<std::size_t>(reply.size(), 5)));
  check_status(tc32);
  if (reply.size() < 4) {
    FUZZ_CHECK(tc32.status == SampleStatus::kBadReply);
  }
  const ChannelReading exact = decode_tc32_reading(bytes.first(std::min<std::size_t>(reply.size(), 4)));
  check_status(exact);
  if (reply.size() >= 4) {
    float f;
    std::memcpy(&f, reply.data(), 4);  // little-endian host, as the device sends it
    const bool sentinel = f == -777.0f || f == -888.0f || f == -999.0f;
    FUZZ_CHECK((exact.status == SampleStatus::kOk) == (std::isfinite(f) && !sentinel));
    if (exact.value) FUZZ_CHECK(*exact.value == static_cast<double>(f));
    if (reply.size() >= 5) FUZZ_CHECK(tc32.status == SampleStatus::kBadReply);
  }
  return 0;
}
