#pragma once
// How numbers travel in Modbus registers. A register is 16 bits; libmodbus
// hands them over as host-order uint16 whose high byte came first on the
// wire. Wider types span two registers, and devices disagree on the order of
// the four bytes A B C D (A most significant): ABCD is big-endian, CDAB swaps
// the words, BADC swaps the bytes in each word, DCBA reverses all four. For
// 16-bit types only the byte order matters (BADC and DCBA swap the bytes).
// Encoding is here too, so the simulator speaks exactly what the reader
// decodes, and both can be tested byte for byte.

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace bosfuse::acquisition {

enum class DataType { kInt16, kUint16, kInt32, kUint32, kFloat32 };
enum class WordOrder { kABCD, kCDAB, kBADC, kDCBA };

int register_count(DataType type);

// Parses "int16", "float32", "ABCD", ... (case-insensitive); nullopt if unknown.
std::optional<DataType> parse_data_type(std::string_view text);
std::optional<WordOrder> parse_word_order(std::string_view text);
std::string_view to_string(DataType type);
std::string_view to_string(WordOrder order);

// `registers` must hold register_count(type) registers.
double decode_registers(std::span<const std::uint16_t> registers, DataType type, WordOrder order);

// Rounds integers to nearest and saturates at the type's limits.
std::vector<std::uint16_t> encode_registers(double value, DataType type, WordOrder order);

}  // namespace bosfuse::acquisition
