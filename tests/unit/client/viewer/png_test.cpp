#include "client/viewer/png.hpp"

#include <gtest/gtest.h>

#include <random>

namespace teleop::viewer {
namespace {

Image random_image(int w, int h, int channels, unsigned seed) {
  Image img;
  img.width = w;
  img.height = h;
  img.channels = channels;
  img.pixels.resize(static_cast<std::size_t>(w * h * channels));
  std::mt19937 rng(seed);
  // smooth gradients plus noise: exercises every filter type
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < channels; ++c) {
        const int v = (x * 3 + y * 5 + c * 40) + static_cast<int>(rng() % 7);
        img.pixels[static_cast<std::size_t>((y * w + x) * channels + c)] =
            static_cast<std::uint8_t>(v);
      }
    }
  }
  return img;
}

TEST(Png, RoundTripsGreyRgbAndRgbaOfOddSizes) {
  for (const int channels : {1, 3, 4}) {
    for (const auto& [w, h] : {std::pair{1, 1}, std::pair{7, 3}, std::pair{33, 17}}) {
      const Image in = random_image(w, h, channels, static_cast<unsigned>(w * 100 + channels));
      const std::vector<std::uint8_t> bytes = encode_png(in);
      Image out;
      std::string error;
      ASSERT_TRUE(decode_png(bytes, out, error)) << error;
      EXPECT_EQ(out.width, w);
      EXPECT_EQ(out.height, h);
      EXPECT_EQ(out.channels, channels);
      EXPECT_EQ(out.pixels, in.pixels) << channels << " channels, " << w << "x" << h;
    }
  }
}

TEST(Png, StartsWithTheSignatureAndCompressesFlatImages) {
  Image flat;
  flat.width = 640;
  flat.height = 480;
  flat.channels = 3;
  flat.pixels.assign(640u * 480u * 3u, 200);
  const auto bytes = encode_png(flat);
  ASSERT_GT(bytes.size(), 8u);
  EXPECT_EQ(bytes[0], 0x89);
  EXPECT_EQ(bytes[1], 'P');
  EXPECT_LT(bytes.size(), 10000u);  // 921600 raw bytes
}

TEST(Png, DecoderRejectsCorruptData) {
  const Image in = random_image(16, 16, 3, 1);
  std::vector<std::uint8_t> bytes = encode_png(in);
  Image out;
  std::string error;
  auto bad = bytes;
  bad[bad.size() / 2] ^= 0x55;  // inside IDAT: its CRC no longer matches
  EXPECT_FALSE(decode_png(bad, out, error));
  EXPECT_NE(error.find("CRC"), std::string::npos) << error;
  bad = bytes;
  bad[0] = 0;
  EXPECT_FALSE(decode_png(bad, out, error));
  bad.assign(bytes.begin(), bytes.begin() + 40);
  EXPECT_FALSE(decode_png(bad, out, error));
}

TEST(Png, EncoderRejectsInconsistentImages) {
  Image img;
  img.width = 4;
  img.height = 4;
  img.channels = 2;
  img.pixels.resize(32);
  EXPECT_THROW(encode_png(img), std::invalid_argument);
  img.channels = 3;
  EXPECT_THROW(encode_png(img), std::invalid_argument);  // 32 != 48 bytes
}

}  // namespace
}  // namespace teleop::viewer
