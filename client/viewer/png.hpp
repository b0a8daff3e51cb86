#pragma once
// A small PNG codec over zlib (RFC 2083): 8-bit grey, RGB or RGBA, non-interlaced. The encoder
// picks a filter per row (the spec's minimum-sum-of-absolute-differences heuristic); the
// decoder reads what the encoder writes (and any PNG of those formats), which is what the
// tests need to look at a snapshot's pixels.
#include <cstdint>
#include <string>
#include <vector>

namespace teleop::viewer {

/// An 8-bit image, rows top to bottom, `channels` bytes per pixel (1 grey, 3 RGB, 4 RGBA).
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<std::uint8_t> pixels;  ///< width * height * channels bytes

  const std::uint8_t* at(int x, int y) const {
    return pixels.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                            static_cast<std::size_t>(x)) *
                               static_cast<std::size_t>(channels);
  }
};

/// Encodes `image` as PNG bytes. @throws std::invalid_argument for a bad size or channel count,
/// std::runtime_error if zlib fails.
std::vector<std::uint8_t> encode_png(const Image& image, int compression_level = 6);

/// Decodes PNG bytes. Returns false and sets `error` for a corrupt file, a bad checksum or an
/// unsupported format (bit depth other than 8, palette, interlace).
bool decode_png(const std::vector<std::uint8_t>& bytes, Image& out, std::string& error);

/// encode_png, then writes the file. Returns false and sets `error` on failure.
bool write_png_file(const std::string& path, const Image& image, std::string& error);

/// Reads and decodes a file. Returns false and sets `error` on failure.
bool read_png_file(const std::string& path, Image& out, std::string& error);

}  // namespace teleop::viewer
