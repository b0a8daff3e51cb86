#pragma once
// CRC-32 as MCAP uses it: the IEEE 802.3 polynomial, reflected (0xEDB88320), initial value and
// final xor 0xFFFFFFFF; the same checksum as zlib's crc32() and `cksum -a crc32b`-style tools.
#include <cstddef>
#include <cstdint>

namespace teleop::record {

/// Extends `crc` (the CRC-32 of the bytes before, 0 for none) over `n` more bytes.
/// crc32_update(crc32_update(0, a, na), b, nb) == CRC-32 of a followed by b.
std::uint32_t crc32_update(std::uint32_t crc, const void* data, std::size_t n);

inline std::uint32_t crc32(const void* data, std::size_t n) { return crc32_update(0, data, n); }

}  // namespace teleop::record
