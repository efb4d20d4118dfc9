#include "render/image.h"

#include <png.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <sstream>

#include "core/errors.h"
#include "core/files.h"

namespace visproxy {
namespace {

std::uint8_t srgb_byte(double linear) {
  const double v = std::clamp(linear, 0.0, 1.0);
  const double encoded = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
  return static_cast<std::uint8_t>(std::lround(255 * encoded));
}

void append_png(png_structp png, png_bytep data, png_size_t length) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), length);
}

}  // namespace

void write_pfm(const std::filesystem::path& path, const Image& image) {
  std::string bytes = "PF\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n-1.0\n";
  bytes.reserve(bytes.size() + image.pixels.size() * 12);
  for (int y = image.height - 1; y >= 0; --y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < 3; ++c) {
        float value = static_cast<float>(image.at(x, y)[c]);
        std::uint32_t raw;
        std::memcpy(&raw, &value, 4);
        if constexpr (std::endian::native == std::endian::big) raw = __builtin_bswap32(raw);
        bytes.append(reinterpret_cast<const char*>(&raw), 4);
      }
  write_file_atomically(path, bytes);
}

Image read_pfm(const std::filesystem::path& path) {
  const std::string bytes = read_file(path);
  std::istringstream header(bytes);
  std::string magic;
  int width = 0, height = 0;
  double scale = 0;
  header >> magic >> width >> height >> scale;
  if (!header || magic != "PF") throw InvalidInputError(path, "not a colour PFM image (expected \"PF\", width, height, scale)");
  if (width <= 0 || height <= 0 || width > 65536 || height > 65536) throw InvalidInputError(path, "bad image size");
  const auto start = static_cast<std::size_t>(header.tellg()) + 1;  // one whitespace byte after the scale
  const std::size_t needed = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 12;
  if (bytes.size() < start + needed) throw InvalidInputError(path, "truncated: fewer pixels than the header says");
  const bool little = scale < 0;
  Image image(width, height);
  const char* data = bytes.data() + start;
  for (int y = height - 1; y >= 0; --y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) {
        std::uint32_t raw;
        std::memcpy(&raw, data, 4);
        data += 4;
        if (little != (std::endian::native == std::endian::little)) raw = __builtin_bswap32(raw);
        float value;
        std::memcpy(&value, &raw, 4);
        image.at(x, y)[c] = value;
      }
  return image;
}

void write_png(const std::filesystem::path& path, const Image& image, double exposure) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    throw IOError(path, "libpng: out of memory");
  }
  std::string bytes;
  std::vector<std::uint8_t> row(static_cast<std::size_t>(image.width) * 3);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw IOError(path, "libpng could not encode the image");
  }
  png_set_write_fn(png, &bytes, append_png, nullptr);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height), 8,
               PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < 3; ++c) row[static_cast<std::size_t>(3 * x + c)] = srgb_byte(exposure * image.at(x, y)[c]);
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  write_file_atomically(path, bytes);
}

double mean_squared_error(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) throw Error("mean squared error of images of different sizes");
  double sum = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) sum += (a.pixels[i] - b.pixels[i]).squaredNorm();
  return a.pixels.empty() ? 0.0 : sum / (3.0 * static_cast<double>(a.pixels.size()));
}

bool all_finite(const Image& image) {
  return std::all_of(image.pixels.begin(), image.pixels.end(), [](const Color& c) { return c.allFinite(); });
}

}  // namespace visproxy
