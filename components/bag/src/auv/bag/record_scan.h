#pragma once
// Walks the records of a buffer (a chunk's records, the summary): the framing every reader
// of this package shares. Internal to auv_bag.

#include <cstdint>
#include <cstdio>
#include <string>

#include "auv/bag/records.h"

namespace auv::bag {

/// "0x1234abcd", as CRCs are shown in damage reports.
inline std::string hex32(uint32_t value) {
  char text[16];
  std::snprintf(text, sizeof(text), "0x%08x", value);
  return text;
}

/// Calls f(opcode, content, content_length, record_offset) for each record of the `size`
/// bytes of `data`. Throws ParseError naming the record and its offset when a record runs
/// past the end, or when f throws ParseError.
template <class F>
void forEachRecord(const uint8_t* data, uint64_t size, F&& f) {
  uint64_t at = 0;
  while (at < size) {
    if (size - at < kRecordHeaderSize) {
      throw ParseError("a record header at offset " + std::to_string(at) + " is cut short");
    }
    const uint8_t opcode = data[at];
    const uint64_t length = readU64(data + at + 1);
    if (length > size - at - kRecordHeaderSize) {
      throw ParseError(opcodeName(opcode) + " record at offset " + std::to_string(at) +
                       " declares " + std::to_string(length) + " bytes, " +
                       std::to_string(size - at - kRecordHeaderSize) + " left");
    }
    try {
      f(opcode, data + at + kRecordHeaderSize, length, at);
    } catch (const ParseError& e) {
      throw ParseError(opcodeName(opcode) + " record at offset " + std::to_string(at) + ": " +
                       e.what());
    }
    at += kRecordHeaderSize + length;
  }
}

}  // namespace auv::bag
