#pragma once
// Reading a step's data back into the core's caches before the step runs (the live loops'
// prewarm phase, RateLoop::sleep_until_lead): one byte of every 64-byte line of an array is
// read and summed. Nothing is written, so a step after a prewarm computes exactly what it
// would have computed without one; the sum is returned so that the reads are not elided.
#include <cstddef>
#include <cstdint>

namespace teleop {

/// Reads one byte per cache line of [p, p + bytes) and returns their sum.
inline std::uint64_t touch_lines(const void* p, std::size_t bytes) {
  if (p == nullptr || bytes == 0) return 0;
  const auto* b = static_cast<const unsigned char*>(p);
  std::uint64_t sum = b[bytes - 1];
  for (std::size_t i = 0; i < bytes; i += 64) sum += b[i];
  return sum;
}

/// touch_lines over a contiguous container (std::vector, std::array, an Eigen dense object).
template <class C>
std::uint64_t touch(const C& c) {
  return touch_lines(c.data(), static_cast<std::size_t>(c.size()) * sizeof(*c.data()));
}

/// Uses a prewarm's sum, so that the compiler keeps the reads that made it.
inline void keep(std::uint64_t sum) { asm volatile("" : : "r"(sum)); }

}  // namespace teleop
