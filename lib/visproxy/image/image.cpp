#include "visproxy/image/image.h"

#include <IexBaseExc.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStdIO.h>
#include <openexr.h>
#include <png.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"

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

bool is_pfm_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

std::string not_finite_pixel(std::size_t x, std::size_t y) {
  return "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") is not finite";
}

// OpenEXR's C++ reader trusts the sizes a file's header states: it allocates an attribute
// of an unknown type at its stated size before reading it, so a few bytes can make it take
// two gigabytes, and it reads some known attributes by their content whatever size they
// claim, so it may find attributes where none begin. It also allocates a block's (a tile's,
// a row of tiles', a chunk of scanlines') decoding buffers before reading the block, at the
// size the header implies. OpenEXRCore, the library's C core, checks every attribute's size
// against its content and the file; a header that its strict check rejects, or whose blocks
// need more than kMaxExrBlockBytes, is not given to the C++ reader.
constexpr std::uint64_t kMaxExrBlockBytes = std::uint64_t{64} << 20;

struct CoreInput {
  std::string_view bytes;
  std::string first_error;
};

// Checks the headers and returns the rows of a block of the first part (a chunk of
// scanlines, or a row of tiles), which parse_exr reads at a time.
int check_exr_headers(std::string_view bytes, const std::filesystem::path& path) {
  CoreInput input{bytes, {}};
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.user_data = &input;
  init.read_fn = [](exr_const_context_t, void* user_data, void* buffer, std::uint64_t size, std::uint64_t offset,
                    exr_stream_error_func_ptr_t) -> std::int64_t {
    const std::string_view all = static_cast<CoreInput*>(user_data)->bytes;
    if (offset >= all.size()) return 0;
    const std::size_t count = static_cast<std::size_t>(std::min<std::uint64_t>(size, all.size() - offset));
    std::memcpy(buffer, all.data() + offset, count);
    return static_cast<std::int64_t>(count);
  };
  init.size_fn = [](exr_const_context_t, void* user_data) -> std::int64_t {
    return static_cast<std::int64_t>(static_cast<CoreInput*>(user_data)->bytes.size());
  };
  init.error_handler_fn = [](exr_const_context_t context, exr_result_t, const char* message) {
    void* user_data = nullptr;
    if (exr_get_user_data(context, &user_data) != EXR_ERR_SUCCESS || user_data == nullptr) return;
    std::string& first = static_cast<CoreInput*>(user_data)->first_error;
    if (first.empty() && message != nullptr) first = message;
  };
  init.flags = EXR_CONTEXT_FLAG_STRICT_HEADER;
  init.max_image_width = init.max_image_height = 65536;
  init.max_tile_width = init.max_tile_height = 65536;
  auto fail = [&](std::string problem) {
    for (char& c : problem)
      if (c == '\n' || c == '\r') c = ' ';
    throw InvalidInputError(path, "not a readable OpenEXR image: " + problem);
  };
  exr_context_t context = nullptr;
  const exr_result_t result = exr_start_read(&context, path.c_str(), &init);
  if (result != EXR_ERR_SUCCESS) {
    if (context != nullptr) exr_finish(&context);
    fail(input.first_error.empty() ? exr_get_default_error_message(result) : input.first_error);
  }
  // The blocks' sizes, part by part: what the C++ reader and parse_exr allocate per block.
  int parts = 0, first_part_rows = 1;
  std::string too_large;
  exr_get_count(context, &parts);
  for (int part = 0; part < parts && too_large.empty(); ++part) {
    exr_storage_t storage = EXR_STORAGE_LAST_TYPE;
    exr_attr_box2i_t window{};
    const exr_attr_chlist_t* channels = nullptr;
    if (exr_get_storage(context, part, &storage) != EXR_ERR_SUCCESS ||
        exr_get_data_window(context, part, &window) != EXR_ERR_SUCCESS ||
        exr_get_channels(context, part, &channels) != EXR_ERR_SUCCESS || channels == nullptr)
      continue;                                         // deep or incomplete parts: the C++ reader rejects them
    std::uint64_t bytes_per_pixel = 3 * sizeof(float);  // parse_exr's own R, G and B
    for (int c = 0; c < channels->num_channels; ++c)
      bytes_per_pixel += channels->entries[c].pixel_type == EXR_PIXEL_HALF ? 2 : 4;
    const auto width = static_cast<std::uint64_t>(std::int64_t{window.max.x} - window.min.x + 1);
    std::uint64_t block_pixels = 0, rows = 1;
    if (storage == EXR_STORAGE_SCANLINE) {
      std::int32_t lines = 1;
      exr_get_scanlines_per_chunk(context, part, &lines);
      rows = static_cast<std::uint64_t>(std::max(lines, 1));
      block_pixels = rows * width;
    } else if (storage == EXR_STORAGE_TILED) {
      std::uint32_t tile_width = 1, tile_height = 1;
      exr_tile_level_mode_t level{};
      exr_tile_round_mode_t round{};
      exr_get_tile_descriptor(context, part, &tile_width, &tile_height, &level, &round);
      rows = std::max<std::uint32_t>(tile_height, 1);
      block_pixels = rows * std::max<std::uint64_t>(tile_width, width);  // a tile, and a row of tiles
    }
    if (block_pixels * bytes_per_pixel > kMaxExrBlockBytes)
      too_large = "a block of " + std::to_string(block_pixels) + " pixels needs " +
                  std::to_string(block_pixels * bytes_per_pixel) + " bytes to decode, more than the 64 MiB allowed";
    if (part == 0) first_part_rows = static_cast<int>(rows);
  }
  exr_finish(&context);
  if (!too_large.empty()) fail(too_large);
  return first_part_rows;
}

// OpenEXR's input from bytes in memory.
class MemoryStream final : public Imf::IStream {
 public:
  MemoryStream(std::string_view bytes, const std::filesystem::path& path) : Imf::IStream(path.c_str()), bytes_(bytes) {}

  bool read(char c[], int n) override {
    if (n < 0 || position_ > bytes_.size() || bytes_.size() - position_ < static_cast<std::uint64_t>(n))
      throw Iex::InputExc("unexpected end of file");
    std::memcpy(c, bytes_.data() + position_, static_cast<std::size_t>(n));
    position_ += static_cast<std::uint64_t>(n);
    return position_ < bytes_.size();
  }
  std::uint64_t tellg() override { return position_; }
  void seekg(std::uint64_t position) override { position_ = position; }  // read() checks it

 private:
  std::string_view bytes_;
  std::uint64_t position_ = 0;
};

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

Image read_pfm(const std::filesystem::path& path) { return parse_pfm(read_file(path), path); }

Image parse_pfm(std::string_view bytes, const std::filesystem::path& path) {
  // "PF", width, height and scale separated by whitespace, then one whitespace byte and the
  // pixels: rows bottom to top, float RGB, little-endian when the scale is negative.
  std::size_t position = 0;
  auto token = [&] {
    while (position < bytes.size() && is_pfm_space(bytes[position])) ++position;
    const std::size_t start = position;
    while (position < bytes.size() && !is_pfm_space(bytes[position])) ++position;
    return bytes.substr(start, position - start);
  };
  if (token() != "PF") throw InvalidInputError(path, "not a colour PFM image (it does not start with \"PF\")");
  int size[2] = {0, 0};
  for (int& extent : size) {
    const std::string_view text = token();
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), extent);
    if (error != std::errc() || end != text.data() + text.size() || extent < 1 || extent > 65536)
      throw InvalidInputError(path, "bad image size (expected a width and a height from 1 to 65536)");
  }
  const std::string_view scale_text = token();
  double scale = 0;
  const auto [end, error] = std::from_chars(scale_text.data(), scale_text.data() + scale_text.size(), scale);
  if (error != std::errc() || end != scale_text.data() + scale_text.size() || !std::isfinite(scale) || scale == 0)
    throw InvalidInputError(path, "bad scale (expected a non-zero number, negative for little-endian pixels)");
  const int width = size[0], height = size[1];
  const std::size_t needed = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 12;
  if (position == bytes.size() || bytes.size() - position - 1 < needed)
    throw InvalidInputError(path, "truncated: fewer pixels than the header says");
  const bool little = scale < 0;
  Image image(width, height);
  const char* data = bytes.data() + position + 1;  // past the one whitespace byte after the scale
  for (int y = height - 1; y >= 0; --y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) {
        std::uint32_t raw;
        std::memcpy(&raw, data, 4);
        data += 4;
        if (little != (std::endian::native == std::endian::little)) raw = __builtin_bswap32(raw);
        float value;
        std::memcpy(&value, &raw, 4);
        if (!std::isfinite(value)) throw InvalidInputError(path, not_finite_pixel(x, y));
        image.at(x, y)[c] = value;
      }
  return image;
}

void write_exr(const std::filesystem::path& path, const Image& image) {
  // Planar float channels for OpenEXR's frame buffer; the file is built in memory and then
  // written atomically like every other output.
  const std::size_t count = image.pixels.size();
  std::vector<float> planes(3 * count);
  for (std::size_t i = 0; i < count; ++i)
    for (std::size_t c = 0; c < 3; ++c) planes[c * count + i] = static_cast<float>(image.pixels[i][static_cast<int>(c)]);
  std::string bytes;
  try {
    Imf::Header header(image.width, image.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    Imf::FrameBuffer frame;
    const char* names[3] = {"R", "G", "B"};
    for (std::size_t c = 0; c < 3; ++c) {
      header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
      frame.insert(names[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes.data() + c * count), sizeof(float),
                                        sizeof(float) * static_cast<std::size_t>(image.width)));
    }
    Imf::StdOSStream stream;
    {
      Imf::OutputFile file(stream, header, 1);
      file.setFrameBuffer(frame);
      file.writePixels(image.height);
    }
    bytes = stream.str();
  } catch (const std::exception& e) {
    throw IOError(path, std::string("OpenEXR could not encode the image: ") + e.what());
  }
  write_file_atomically(path, bytes);
}

Image read_exr(const std::filesystem::path& path) { return parse_exr(read_file(path), path); }

Image parse_exr(std::string_view bytes, const std::filesystem::path& path) {
  const int block_rows = check_exr_headers(bytes, path);
  try {
    MemoryStream stream(bytes, path);
    Imf::InputFile file(stream, 1);
    const Imath::Box2i window = file.header().dataWindow();
    const std::int64_t width = std::int64_t{window.max.x} - window.min.x + 1;
    const std::int64_t height = std::int64_t{window.max.y} - window.min.y + 1;
    if (width <= 0 || height <= 0 || width > 65536 || height > 65536)
      throw InvalidInputError(path, "bad image size (expected a width and a height from 1 to 65536)");
    // Bands of whole blocks, at least 16 rows, so that memory grows with the pixels actually
    // decoded: a short file claiming a large image fails at its first missing block.
    const std::int64_t band_rows = block_rows * ((16 + block_rows - 1) / block_rows);
    const auto row_pixels = static_cast<std::size_t>(width);
    std::vector<float> planes(3 * row_pixels * static_cast<std::size_t>(std::min(band_rows, height)));
    Image image;
    image.width = static_cast<int>(width);
    image.height = static_cast<int>(height);
    const char* names[3] = {"R", "G", "B"};
    for (std::int64_t top = window.min.y; top <= window.max.y; top += band_rows) {
      const std::int64_t rows = std::min(band_rows, std::int64_t{window.max.y} - top + 1);
      const std::size_t band_pixels = row_pixels * static_cast<std::size_t>(rows);
      std::fill(planes.begin(), planes.end(), 0.0f);  // missing channels read as 0
      Imf::FrameBuffer frame;
      for (std::size_t c = 0; c < 3; ++c)  // the band's slices start at its top left pixel
        frame.insert(names[c], Imf::Slice::Make(Imf::FLOAT, planes.data() + c * band_pixels,
                                                Imath::V2i(window.min.x, static_cast<int>(top)), width, rows,
                                                sizeof(float), sizeof(float) * row_pixels, 1, 1, 0.0));
      file.setFrameBuffer(frame);
      file.readPixels(static_cast<int>(top), static_cast<int>(top + rows - 1));
      for (std::size_t i = 0; i < band_pixels; ++i) {
        const Color pixel(planes[i], planes[band_pixels + i], planes[2 * band_pixels + i]);
        if (!pixel.allFinite())
          throw InvalidInputError(
              path, not_finite_pixel(i % row_pixels, static_cast<std::size_t>(top - window.min.y) + i / row_pixels));
        image.pixels.push_back(pixel);
      }
    }
    return image;
  } catch (const InvalidInputError&) {
    throw;
  } catch (const std::exception& e) {
    std::string problem = e.what();
    for (char& c : problem)
      if (c == '\n' || c == '\r') c = ' ';
    throw InvalidInputError(path, "not a readable OpenEXR image: " + problem);
  }
}

bool is_linear_image_path(const std::filesystem::path& path) {
  const std::string extension = path.extension().string();
  return extension == ".pfm" || extension == ".exr";
}

void write_linear_image(const std::filesystem::path& path, const Image& image) {
  if (path.extension() == ".pfm") return write_pfm(path, image);
  if (path.extension() == ".exr") return write_exr(path, image);
  throw InvalidInputError(path, "unsupported image format (use .pfm or .exr)");
}

Image read_linear_image(const std::filesystem::path& path) {
  if (path.extension() == ".pfm") return read_pfm(path);
  if (path.extension() == ".exr") return read_exr(path);
  throw InvalidInputError(path, "unsupported image format (use .pfm or .exr)");
}

std::string encode_png(const Image& image, double exposure) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    throw Error("libpng: out of memory");
  }
  std::string bytes;
  std::vector<std::uint8_t> row(static_cast<std::size_t>(image.width) * 3);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw Error("libpng could not encode a " + std::to_string(image.width) + " x " + std::to_string(image.height) + " image");
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
  return bytes;
}

void write_png(const std::filesystem::path& path, const Image& image, double exposure) {
  write_file_atomically(path, encode_png(image, exposure));
}

double mean_squared_error(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) throw Error("mean squared error of images of different sizes");
  double sum = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) sum += (a.pixels[i] - b.pixels[i]).squaredNorm();
  return a.pixels.empty() ? 0.0 : sum / (3.0 * static_cast<double>(a.pixels.size()));
}

Image squared_error_map(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) throw Error("error map of images of different sizes");
  Image map(a.width, a.height);
  for (std::size_t i = 0; i < a.pixels.size(); ++i) map.pixels[i] = Color::Constant((a.pixels[i] - b.pixels[i]).squaredNorm() / 3.0);
  return map;
}

bool all_finite(const Image& image) {
  return std::all_of(image.pixels.begin(), image.pixels.end(), [](const Color& c) { return c.allFinite(); });
}

}  // namespace visproxy
