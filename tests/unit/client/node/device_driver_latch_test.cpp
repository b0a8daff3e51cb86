// Which external driver the master believes (client/node/device_driver_latch.hpp): the first
// writer until it has been silent past kSilentNs, every other writer's samples meanwhile refused
// and counted.
#include "client/node/device_driver_latch.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace teleop::master {
namespace {

DeviceDriverLatch::Writer writer(std::uint8_t id) {
  DeviceDriverLatch::Writer w;
  w.value[0] = id;
  w.value[15] = 1;
  return w;
}

constexpr std::int64_t kT0 = 5'000'000'000;  // a steady clock's reading [ns]
constexpr std::int64_t kMs = 1'000'000;

TEST(DeviceDriverLatch, TheFirstWriterIsTheDriverAndAnotherOneMeanwhileIsIgnored) {
  DeviceDriverLatch latch;
  const auto a = writer(1);
  const auto b = writer(2);
  EXPECT_TRUE(latch.accept(a, kT0));
  EXPECT_FALSE(latch.accept(b, kT0 + 1 * kMs));
  EXPECT_TRUE(latch.accept(a, kT0 + 2 * kMs));
  // b's samples keep coming while a stays live: each one refused and counted
  for (int k = 1; k <= 5; ++k) {
    EXPECT_TRUE(latch.accept(a, kT0 + (2 + 50 * k) * kMs));
    EXPECT_FALSE(latch.accept(b, kT0 + (3 + 50 * k) * kMs));
  }
  EXPECT_EQ(latch.ignored(), 6u);
}

TEST(DeviceDriverLatch, AnotherWriterTakesOverOnlyAfterTheDriverFellSilent) {
  DeviceDriverLatch latch;
  const auto a = writer(1);
  const auto b = writer(2);
  ASSERT_TRUE(latch.accept(a, kT0));
  // exactly kSilentNs of silence: a is still the driver
  EXPECT_FALSE(latch.accept(b, kT0 + DeviceDriverLatch::kSilentNs));
  // a refused sample does not keep the driver alive: past kSilentNs since a's last, b takes over
  EXPECT_TRUE(latch.accept(b, kT0 + DeviceDriverLatch::kSilentNs + 1));
  EXPECT_FALSE(latch.accept(a, kT0 + DeviceDriverLatch::kSilentNs + 2 * kMs));
  EXPECT_EQ(latch.ignored(), 2u);
}

}  // namespace
}  // namespace teleop::master
