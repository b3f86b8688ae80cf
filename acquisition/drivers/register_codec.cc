#include "acquisition/drivers/register_codec.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace bosfuse::acquisition {
namespace {

constexpr std::array<std::string_view, 5> kDataTypeNames = {"int16", "uint16", "int32", "uint32", "float32"};
constexpr std::array<std::string_view, 4> kOrderNames = {"ABCD", "CDAB", "BADC", "DCBA"};

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) { return std::tolower(x) == std::tolower(y); });
}

template <std::size_t N>
std::optional<std::size_t> find_name(const std::array<std::string_view, N>& names, std::string_view text) {
  for (std::size_t i = 0; i < N; ++i) {
    if (iequals(names[i], text)) return i;
  }
  return std::nullopt;
}

std::uint16_t swap_bytes(std::uint16_t word) { return static_cast<std::uint16_t>((word << 8) | (word >> 8)); }

bool swaps_bytes(WordOrder order) { return order == WordOrder::kBADC || order == WordOrder::kDCBA; }
bool swaps_words(WordOrder order) { return order == WordOrder::kCDAB || order == WordOrder::kDCBA; }

// The 16-bit words as they should be for big-endian (ABCD) reading.
std::uint16_t normalise_word(std::uint16_t word, WordOrder order) {
  return swaps_bytes(order) ? swap_bytes(word) : word;
}

std::uint32_t decode_u32(std::span<const std::uint16_t> r, WordOrder order) {
  std::uint16_t high = normalise_word(r[0], order);
  std::uint16_t low = normalise_word(r[1], order);
  if (swaps_words(order)) std::swap(high, low);
  return (static_cast<std::uint32_t>(high) << 16) | low;
}

std::vector<std::uint16_t> encode_u32(std::uint32_t bits, WordOrder order) {
  std::uint16_t high = static_cast<std::uint16_t>(bits >> 16);
  std::uint16_t low = static_cast<std::uint16_t>(bits & 0xFFFF);
  if (swaps_words(order)) std::swap(high, low);
  return {normalise_word(high, order), normalise_word(low, order)};
}

template <typename T>
T saturate(double value) {
  if (std::isnan(value)) return 0;
  const double rounded = std::nearbyint(value);
  if (rounded <= static_cast<double>(std::numeric_limits<T>::min())) return std::numeric_limits<T>::min();
  if (rounded >= static_cast<double>(std::numeric_limits<T>::max())) return std::numeric_limits<T>::max();
  return static_cast<T>(rounded);
}

}  // namespace

int register_count(DataType type) { return type == DataType::kInt16 || type == DataType::kUint16 ? 1 : 2; }

std::optional<DataType> parse_data_type(std::string_view text) {
  if (auto i = find_name(kDataTypeNames, text)) return static_cast<DataType>(*i);
  return std::nullopt;
}

std::optional<WordOrder> parse_word_order(std::string_view text) {
  if (auto i = find_name(kOrderNames, text)) return static_cast<WordOrder>(*i);
  return std::nullopt;
}

std::string_view to_string(DataType type) { return kDataTypeNames.at(static_cast<std::size_t>(type)); }
std::string_view to_string(WordOrder order) { return kOrderNames.at(static_cast<std::size_t>(order)); }

double decode_registers(std::span<const std::uint16_t> registers, DataType type, WordOrder order) {
  if (registers.size() < static_cast<std::size_t>(register_count(type))) {
    throw std::invalid_argument("decode_registers: " + std::string(to_string(type)) + " needs " +
                                std::to_string(register_count(type)) + " registers, got " +
                                std::to_string(registers.size()));
  }
  switch (type) {
    case DataType::kUint16:
      return normalise_word(registers[0], order);
    case DataType::kInt16:
      return static_cast<std::int16_t>(normalise_word(registers[0], order));
    case DataType::kUint32:
      return decode_u32(registers, order);
    case DataType::kInt32:
      return static_cast<std::int32_t>(decode_u32(registers, order));
    case DataType::kFloat32:
      return std::bit_cast<float>(decode_u32(registers, order));
  }
  throw std::invalid_argument("decode_registers: unknown data type");
}

std::vector<std::uint16_t> encode_registers(double value, DataType type, WordOrder order) {
  switch (type) {
    case DataType::kUint16:
      return {normalise_word(saturate<std::uint16_t>(value), order)};
    case DataType::kInt16:
      return {normalise_word(static_cast<std::uint16_t>(saturate<std::int16_t>(value)), order)};
    case DataType::kUint32:
      return encode_u32(saturate<std::uint32_t>(value), order);
    case DataType::kInt32:
      return encode_u32(static_cast<std::uint32_t>(saturate<std::int32_t>(value)), order);
    case DataType::kFloat32:
      return encode_u32(std::bit_cast<std::uint32_t>(static_cast<float>(value)), order);
  }
  throw std::invalid_argument("encode_registers: unknown data type");
}

}  // namespace bosfuse::acquisition
