#include "client/viewer/png.hpp"

#include <zlib.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

namespace teleop::viewer {
namespace {

constexpr std::array<std::uint8_t, 8> kSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  out.push_back(static_cast<std::uint8_t>(v >> 24));
  out.push_back(static_cast<std::uint8_t>(v >> 16));
  out.push_back(static_cast<std::uint8_t>(v >> 8));
  out.push_back(static_cast<std::uint8_t>(v));
}

std::uint32_t get_u32(const std::uint8_t* p) {
  return (static_cast<std::uint32_t>(p[0]) << 24) | (static_cast<std::uint32_t>(p[1]) << 16) |
         (static_cast<std::uint32_t>(p[2]) << 8) | static_cast<std::uint32_t>(p[3]);
}

/// Appends one chunk: length, type, data, CRC-32 of type and data.
void put_chunk(std::vector<std::uint8_t>& out, const char type[4], const std::uint8_t* data,
               std::size_t size) {
  put_u32(out, static_cast<std::uint32_t>(size));
  const std::size_t type_at = out.size();
  out.insert(out.end(), type, type + 4);
  if (size > 0) out.insert(out.end(), data, data + size);
  const uLong crc = crc32(0L, out.data() + type_at, static_cast<uInt>(size + 4));
  put_u32(out, static_cast<std::uint32_t>(crc));
}

/// The Paeth predictor of the PNG spec.
int paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  if (pb <= pc) return b;
  return c;
}

/// Prediction of filter `type` from the left (a), upper (b) and upper-left (c) bytes.
int predict(int type, int a, int b, int c) {
  switch (type) {
    case 1:
      return a;
    case 2:
      return b;
    case 3:
      return (a + b) / 2;
    case 4:
      return paeth(a, b, c);
    default:
      return 0;
  }
}

/// Applies filter `type` to `row` (`prev` is the row above, nullptr for the first row) when
/// `sign` is -1 (encoding, into `out`), or undoes it when `sign` is +1 (decoding: `row` is the
/// filtered input, `out` the reconstruction and may alias it).
void apply_filter(int type, int sign, const std::uint8_t* row, const std::uint8_t* prev,
                  std::size_t n, std::size_t bpp, std::uint8_t* out) {
  for (std::size_t i = 0; i < n; ++i) {
    // decoding predicts from reconstructed bytes (out), encoding from the raw row
    const std::uint8_t* left = sign > 0 ? out : row;
    const int a = i >= bpp ? left[i - bpp] : 0;
    const int b = prev ? prev[i] : 0;
    const int c = (prev && i >= bpp) ? prev[i - bpp] : 0;
    out[i] = static_cast<std::uint8_t>(row[i] + sign * predict(type, a, b, c));
  }
}

int color_type_for(int channels) {
  switch (channels) {
    case 1:
      return 0;
    case 3:
      return 2;
    case 4:
      return 6;
    default:
      return -1;
  }
}

}  // namespace

std::vector<std::uint8_t> encode_png(const Image& image, int compression_level) {
  const int color_type = color_type_for(image.channels);
  if (color_type < 0) throw std::invalid_argument("encode_png: channels must be 1, 3 or 4");
  if (image.width <= 0 || image.height <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) *
                                 static_cast<std::size_t>(image.height) *
                                 static_cast<std::size_t>(image.channels)) {
    throw std::invalid_argument("encode_png: size does not match the pixel buffer");
  }
  const int bpp = image.channels;
  const std::size_t stride = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(bpp);

  // filtered scanlines: one filter byte, then the filtered row
  std::vector<std::uint8_t> raw((stride + 1) * static_cast<std::size_t>(image.height));
  std::vector<std::uint8_t> candidate(stride);
  for (int y = 0; y < image.height; ++y) {
    const std::uint8_t* row = image.pixels.data() + static_cast<std::size_t>(y) * stride;
    const std::uint8_t* prev = y > 0 ? row - stride : nullptr;
    std::uint8_t* dst = raw.data() + static_cast<std::size_t>(y) * (stride + 1);
    std::uint64_t best_cost = UINT64_MAX;
    for (int type = 0; type <= 4; ++type) {
      apply_filter(type, -1, row, prev, stride, static_cast<std::size_t>(bpp), candidate.data());
      std::uint64_t cost = 0;  // sum of |value| with bytes read as signed
      for (std::size_t i = 0; i < stride; ++i) {
        cost += static_cast<std::uint64_t>(
            std::abs(static_cast<int>(static_cast<std::int8_t>(candidate[i]))));
      }
      if (cost < best_cost) {
        best_cost = cost;
        dst[0] = static_cast<std::uint8_t>(type);
        std::memcpy(dst + 1, candidate.data(), stride);
      }
    }
  }

  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::vector<std::uint8_t> packed(packed_size);
  if (compress2(packed.data(), &packed_size, raw.data(), static_cast<uLong>(raw.size()),
                compression_level) != Z_OK) {
    throw std::runtime_error("encode_png: zlib compress2 failed");
  }
  packed.resize(packed_size);

  std::vector<std::uint8_t> out(kSignature.begin(), kSignature.end());
  std::vector<std::uint8_t> ihdr;
  put_u32(ihdr, static_cast<std::uint32_t>(image.width));
  put_u32(ihdr, static_cast<std::uint32_t>(image.height));
  ihdr.push_back(8);  // bit depth
  ihdr.push_back(static_cast<std::uint8_t>(color_type));
  ihdr.push_back(0);  // compression: deflate
  ihdr.push_back(0);  // filter method 0
  ihdr.push_back(0);  // no interlace
  put_chunk(out, "IHDR", ihdr.data(), ihdr.size());
  static const char kSoftware[] = "Software\0teleop_viewer";
  put_chunk(out, "tEXt", reinterpret_cast<const std::uint8_t*>(kSoftware), sizeof(kSoftware) - 1);
  put_chunk(out, "IDAT", packed.data(), packed.size());
  put_chunk(out, "IEND", nullptr, 0);
  return out;
}

bool decode_png(const std::vector<std::uint8_t>& bytes, Image& out, std::string& error) {
  if (bytes.size() < kSignature.size() ||
      std::memcmp(bytes.data(), kSignature.data(), kSignature.size()) != 0) {
    error = "not a PNG file (bad signature)";
    return false;
  }
  std::size_t p = kSignature.size();
  int width = 0, height = 0, channels = 0;
  bool have_header = false, have_end = false;
  std::vector<std::uint8_t> packed;
  while (p + 12 <= bytes.size()) {
    const std::uint32_t len = get_u32(bytes.data() + p);
    if (len > bytes.size() - p - 12) {
      error = "truncated chunk";
      return false;
    }
    const std::uint8_t* type = bytes.data() + p + 4;
    const std::uint8_t* data = type + 4;
    const std::uint32_t crc = get_u32(data + len);
    if (crc != static_cast<std::uint32_t>(crc32(0L, type, static_cast<uInt>(len + 4)))) {
      error = "bad CRC in chunk " + std::string(reinterpret_cast<const char*>(type), 4);
      return false;
    }
    if (std::memcmp(type, "IHDR", 4) == 0) {
      if (len != 13) {
        error = "bad IHDR length";
        return false;
      }
      width = static_cast<int>(get_u32(data));
      height = static_cast<int>(get_u32(data + 4));
      const int depth = data[8], color = data[9], interlace = data[12];
      if (depth != 8 || interlace != 0 || data[10] != 0 || data[11] != 0) {
        error = "unsupported PNG: bit depth " + std::to_string(depth) + ", interlace " +
                std::to_string(interlace) + " (only 8-bit non-interlaced)";
        return false;
      }
      channels = color == 0 ? 1 : color == 2 ? 3 : color == 6 ? 4 : 0;
      if (channels == 0 || width <= 0 || height <= 0) {
        error = "unsupported PNG colour type " + std::to_string(color);
        return false;
      }
      have_header = true;
    } else if (std::memcmp(type, "IDAT", 4) == 0) {
      packed.insert(packed.end(), data, data + len);
    } else if (std::memcmp(type, "IEND", 4) == 0) {
      have_end = true;
      break;
    }
    p += 12 + len;
  }
  if (!have_header || !have_end || packed.empty()) {
    error = "missing IHDR, IDAT or IEND";
    return false;
  }
  const std::size_t stride = static_cast<std::size_t>(width) * static_cast<std::size_t>(channels);
  std::vector<std::uint8_t> raw((stride + 1) * static_cast<std::size_t>(height));
  uLongf raw_size = static_cast<uLongf>(raw.size());
  if (uncompress(raw.data(), &raw_size, packed.data(), static_cast<uLong>(packed.size())) != Z_OK ||
      raw_size != raw.size()) {
    error = "corrupt image data (inflate failed or wrong size)";
    return false;
  }
  out.width = width;
  out.height = height;
  out.channels = channels;
  out.pixels.resize(stride * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* src = raw.data() + static_cast<std::size_t>(y) * (stride + 1);
    std::uint8_t* row = out.pixels.data() + static_cast<std::size_t>(y) * stride;
    if (src[0] > 4) {
      error = "bad filter type " + std::to_string(src[0]) + " in row " + std::to_string(y);
      return false;
    }
    apply_filter(src[0], +1, src + 1, y > 0 ? row - stride : nullptr, stride,
                 static_cast<std::size_t>(channels), row);
  }
  return true;
}

bool write_png_file(const std::string& path, const Image& image, std::string& error) {
  std::vector<std::uint8_t> bytes;
  try {
    bytes = encode_png(image);
  } catch (const std::exception& e) {
    error = e.what();
    return false;
  }
  std::ofstream f(path, std::ios::binary);
  if (!f) {
    error = "cannot open " + path + " for writing";
    return false;
  }
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!f) {
    error = "cannot write " + path;
    return false;
  }
  return true;
}

bool read_png_file(const std::string& path, Image& out, std::string& error) {
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    error = "cannot open " + path;
    return false;
  }
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(f)),
                                        std::istreambuf_iterator<char>());
  return decode_png(bytes, out, error);
}

}  // namespace teleop::viewer
