#pragma once
// Linear RGB images: PFM for metrics, tone-mapped PNG for people, and the error between two.

#include <filesystem>
#include <vector>

#include "scene/scene.h"

namespace visproxy {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<Color> pixels;  ///< row-major, top row first

  Image() = default;
  Image(int w, int h) : width(w), height(h), pixels(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), Color::Zero()) {}
  Color& at(int x, int y) { return pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)]; }
  const Color& at(int x, int y) const {
    return pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
  }
};

/// Portable float map, little-endian RGB (scale -1), rows bottom to top as the format
/// requires. Values are stored as float.
void write_pfm(const std::filesystem::path& path, const Image& image);
/// Reads a colour PFM of either byte order; throws InvalidInputError naming the file.
Image read_pfm(const std::filesystem::path& path);

/// 8-bit sRGB PNG of exposure * value (values above 1 clip), through libpng.
void write_png(const std::filesystem::path& path, const Image& image, double exposure = 1.0);

/// Mean over pixels and channels of the squared difference; both images the same size.
double mean_squared_error(const Image& a, const Image& b);

/// True when every channel of every pixel is finite.
bool all_finite(const Image& image);

}  // namespace visproxy
