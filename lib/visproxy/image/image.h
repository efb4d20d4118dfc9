#pragma once
// Linear RGB images: PFM or OpenEXR for metrics, tone-mapped PNG for people, and the error
// between two.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "visproxy/scene/scene.h"

namespace visproxy {

/// The mean of a colour's channels: the brightness figures (error bounds, clamped energy,
/// relative errors) are taken on.
inline double luminance(const Color& c) { return (c.x() + c.y() + c.z()) / 3; }

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
/// Reads a colour PFM of either byte order: "PF", width and height (1 to 65536), a non-zero
/// scale (negative: little-endian), one whitespace byte, the pixels. Throws InvalidInputError
/// naming the file when the header is malformed, pixels are missing or one is not finite.
Image read_pfm(const std::filesystem::path& path);
/// The same from the file's bytes; `path` names it in errors.
Image parse_pfm(std::string_view bytes, const std::filesystem::path& path);

/// OpenEXR, scanlines of 32-bit float R, G, B channels, ZIP-compressed (lossless).
void write_exr(const std::filesystem::path& path, const Image& image);
/// Reads the R, G and B channels of an OpenEXR image (any pixel type; missing channels
/// read as 0); throws InvalidInputError naming the file when OpenEXR cannot read it, its
/// header fails OpenEXRCore's strict check, it is larger than 65536 pixels on a side, a
/// block (chunk of scanlines, tile, row of tiles) needs more than 64 MiB to decode, or a
/// pixel is not finite.
Image read_exr(const std::filesystem::path& path);
/// The same from the file's bytes, through an Imf::IStream over them; `path` names it in errors.
Image parse_exr(std::string_view bytes, const std::filesystem::path& path);

/// Whether the linear formats know this extension (".pfm", ".exr").
bool is_linear_image_path(const std::filesystem::path& path);
/// write_pfm or write_exr by the extension; InvalidInputError for any other.
void write_linear_image(const std::filesystem::path& path, const Image& image);
/// read_pfm or read_exr by the extension; InvalidInputError for any other.
Image read_linear_image(const std::filesystem::path& path);

/// 8-bit sRGB PNG of exposure * value (values above 1 clip), through libpng: the file's bytes.
std::string encode_png(const Image& image, double exposure = 1.0);
/// encode_png written to `path` atomically.
void write_png(const std::filesystem::path& path, const Image& image, double exposure = 1.0);

/// Mean over pixels and channels of the squared difference; both images the same size.
double mean_squared_error(const Image& a, const Image& b);

/// Per pixel squared error |a - b|^2 / 3 (mean over the channels), as a grey image.
Image squared_error_map(const Image& a, const Image& b);

/// True when every channel of every pixel is finite.
bool all_finite(const Image& image);

}  // namespace visproxy
