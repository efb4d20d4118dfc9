#include "visproxy/image/image.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "visproxy/core/errors.h"
#include "visproxy/core/files.h"
#include "test_support.h"

namespace visproxy {
namespace {

// A small image whose values are exact in float.
Image sample_image(int width, int height) {
  Image image(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) image.at(x, y) = Color(0.25 * x, 0.5 * y, 0.125 * (x + y) + 1);
  return image;
}

// Floats in the byte order `big` names.
std::string floats(std::initializer_list<float> values, bool big) {
  std::string bytes;
  for (float value : values) {
    std::uint32_t raw;
    std::memcpy(&raw, &value, 4);
    if (big == (std::endian::native == std::endian::little)) raw = __builtin_bswap32(raw);
    bytes.append(reinterpret_cast<const char*>(&raw), 4);
  }
  return bytes;
}

// The message parse_pfm gives, or "accepted".
std::string pfm_error(const std::string& bytes) {
  try {
    parse_pfm(bytes, "image.pfm");
    return "accepted";
  } catch (const InvalidInputError& error) {
    return error.what();
  }
}

using ImageFile = testing::ScratchFolder;

TEST_F(ImageFile, PfmRoundTripsAndReadsFromMemory) {
  const Image image = sample_image(3, 2);
  write_pfm(folder_ / "image.pfm", image);
  EXPECT_EQ(read_pfm(folder_ / "image.pfm").pixels, image.pixels);
  EXPECT_EQ(parse_pfm(read_file(folder_ / "image.pfm"), "image.pfm").pixels, image.pixels);
}

TEST(ParsePfm, BigEndianAndSpacing) {
  // A positive scale means big-endian; the bottom row comes first.
  const Image image = parse_pfm("PF\n1   2\t1.0\n" + floats({1, 2, 3, 4, 5, 6}, true), "image.pfm");
  ASSERT_EQ(image.width, 1);
  ASSERT_EQ(image.height, 2);
  EXPECT_EQ(image.at(0, 1), Color(1, 2, 3));
  EXPECT_EQ(image.at(0, 0), Color(4, 5, 6));
}

TEST(ParsePfm, RejectsMalformedHeadersAndPixels) {
  const std::string pixel = floats({1, 2, 3}, false);
  EXPECT_EQ(pfm_error("Pf\n1 1\n-1.0\n" + pixel), "image.pfm: not a colour PFM image (it does not start with \"PF\")");
  EXPECT_EQ(pfm_error("PF\n0 1\n-1.0\n" + pixel),
            "image.pfm: bad image size (expected a width and a height from 1 to 65536)");
  EXPECT_EQ(pfm_error("PF\n1 1.0\n-1.0\n" + pixel),
            "image.pfm: bad image size (expected a width and a height from 1 to 65536)");
  EXPECT_EQ(pfm_error("PF\n65537 1\n-1.0\n" + pixel),
            "image.pfm: bad image size (expected a width and a height from 1 to 65536)");
  EXPECT_EQ(pfm_error("PF\n1 1\n0\n" + pixel),
            "image.pfm: bad scale (expected a non-zero number, negative for little-endian pixels)");
  EXPECT_EQ(pfm_error("PF\n2 1\n-1.0\n" + pixel), "image.pfm: truncated: fewer pixels than the header says");
  // A header that ends the file: the pixels are missing, not the header's own bytes.
  EXPECT_EQ(pfm_error("PF\n1 1\n-1.000000000000"), "image.pfm: truncated: fewer pixels than the header says");
  EXPECT_EQ(pfm_error("PF\n1 1\n-1.0\n" + floats({1, std::numeric_limits<float>::infinity(), 3}, false)),
            "image.pfm: pixel (0, 0) is not finite");
}

// fuzz_readers (minimised): a height of "1.0" was read as 1 with the scale ".0", and a NaN
// pixel was accepted.
TEST(ParsePfm, FuzzFinding) {
  const std::string bytes("PF\n2 1.0\n\0\xff\xff\xff\xff\0\0A\0\0\0?\xff\0\0\0\0A\0\0\0??", 33);
  EXPECT_NE(pfm_error(bytes), "accepted");
  EXPECT_EQ(pfm_error("PF\n2 1\n1.0\n" + floats({1, 2, 3, std::nanf(""), 0, 0}, true)),
            "image.pfm: pixel (1, 0) is not finite");
}

// The message parse_exr gives, or "accepted".
std::string exr_error(const std::string& bytes) {
  try {
    parse_exr(bytes, "image.exr");
    return "accepted";
  } catch (const InvalidInputError& error) {
    return error.what();
  }
}

TEST_F(ImageFile, ExrRoundTripsAndReadsFromMemory) {
  const Image image = sample_image(5, 3);
  write_exr(folder_ / "image.exr", image);
  EXPECT_EQ(read_exr(folder_ / "image.exr").pixels, image.pixels);
  const std::string bytes = read_file(folder_ / "image.exr");
  EXPECT_EQ(parse_exr(bytes, "image.exr").pixels, image.pixels);
  EXPECT_EQ(exr_error(bytes.substr(0, bytes.size() / 2)).rfind("image.exr: not a readable OpenEXR image: ", 0), 0u);
  EXPECT_EQ(exr_error("not an image").rfind("image.exr: not a readable OpenEXR image: ", 0), 0u);
}

// fuzz_readers: an image holding NaN or infinity was accepted.
TEST_F(ImageFile, ExrPixelsMustBeFinite) {
  Image image = sample_image(4, 2);
  image.at(3, 1) = Color(0, std::numeric_limits<double>::quiet_NaN(), 0);
  write_exr(folder_ / "nan.exr", image);
  EXPECT_EQ(exr_error(read_file(folder_ / "nan.exr")), "image.exr: pixel (3, 1) is not finite");
  image.at(3, 1) = Color(0, 0, 1e39);  // beyond float: infinity once stored
  write_exr(folder_ / "inf.exr", image);
  EXPECT_EQ(exr_error(read_file(folder_ / "inf.exr")), "image.exr: pixel (3, 1) is not finite");
}

// The bytes of a 2 by 2 OpenEXR image with one more attribute at the end of its header. Its
// one ZIP block (16 rows) moves by the attribute's size, and so does the offset to it.
std::string exr_with_attribute(const std::filesystem::path& folder, const std::string& attribute) {
  write_exr(folder / "base.exr", sample_image(2, 2));
  std::string bytes = read_file(folder / "base.exr");
  std::size_t position = 8;  // past the magic number and the version
  for (;;) {                 // name, type, size, value, until the empty name ending the header
    const std::size_t name_end = bytes.find('\0', position);
    if (name_end == position) break;
    position = bytes.find('\0', name_end + 1) + 1;
    std::int32_t size;
    std::memcpy(&size, bytes.data() + position, 4);  // little-endian, as on the machines visproxy runs on
    position += 4 + static_cast<std::size_t>(size);
  }
  bytes.insert(position, attribute);
  const std::size_t offset_table = position + attribute.size() + 1;  // after the header's empty name
  std::uint64_t offset;
  std::memcpy(&offset, bytes.data() + offset_table, 8);
  offset += attribute.size();
  std::memcpy(bytes.data() + offset_table, &offset, 8);
  return bytes;
}

// fuzz_readers: OpenEXR's C++ reader allocated header attributes at the sizes their files
// claim. An 88-byte input with an attribute of an unknown type claiming 1633943552 bytes, and
// a 446-byte one whose channel list claims fewer bytes than it holds, so that the reader
// took the rest for an attribute claiming 1660944384 bytes, made it allocate them before
// finding the files too short. Such headers are rejected first.
TEST_F(ImageFile, ExrHeadersAreCheckedBeforeOpenExrAllocates) {
  const std::string unknown = std::string("extra\0unknowntype\0", 18);
  EXPECT_EQ(exr_error(exr_with_attribute(folder_, unknown + std::string("\x00\x00\x64\x61", 4) + "abcd")),
            "image.exr: not a readable OpenEXR image: Attribute 'extra', type 'unknowntype': Invalid size 1633943552");
  EXPECT_EQ(exr_error(exr_with_attribute(folder_, unknown + std::string("\xff\xff\xff\xff", 4))),
            "image.exr: not a readable OpenEXR image: Attribute 'extra', type 'unknowntype': Invalid negative size -1");
  // An attribute of a type OpenEXR does not know, of the size it claims, is read past.
  EXPECT_EQ(exr_error(exr_with_attribute(folder_, unknown + std::string("\x04\x00\x00\x00", 4) + "abcd")), "accepted");

  // A channel list claiming 19 + 8 bytes holds 19 ("R", float, linear 0, reserved,
  // sampling 1 by 1, the empty name ending the list); its last 8 bytes would be read as an
  // attribute "x" of type "y" claiming 1660944384 bytes.
  write_exr(folder_ / "base.exr", sample_image(2, 2));
  std::string bytes = read_file(folder_ / "base.exr");
  const std::string channels = std::string("channels\0chlist\0", 16);
  const std::size_t size_at = bytes.find(channels) + channels.size();
  std::int32_t size;
  std::memcpy(&size, bytes.data() + size_at, 4);
  const std::string hidden = std::string("x\0y\0\x00\x00\x00\x63", 8);
  size += static_cast<std::int32_t>(hidden.size());
  std::memcpy(bytes.data() + size_at, &size, 4);
  bytes.insert(size_at + 4 + static_cast<std::size_t>(size) - hidden.size(), hidden);
  EXPECT_EQ(exr_error(bytes),
            "image.exr: not a readable OpenEXR image: Attribute 'x', type 'y': Invalid size 1660944384");

  EXPECT_EQ(exr_error(std::string("\x76\x2f\x31\x01\x02\x00\x00\x00", 8) + "channels"),
            "image.exr: not a readable OpenEXR image: End of file attempting to read header");
  EXPECT_EQ(exr_error("v/1"), "image.exr: not a readable OpenEXR image: Unable to read magic and version flags");
}

std::string corpus_file(const char* name) {
  return read_file(std::filesystem::path(VISPROXY_SOURCE_DIR) / "tests/fuzz/corpus" / name)
      .substr(1);  // past the selector
}

TEST_F(ImageFile, ExrIsReadInBandsOfBlocks) {
  const Image tall = sample_image(7, 53);  // four bands of 16 rows, the last one short
  write_exr(folder_ / "tall.exr", tall);
  EXPECT_EQ(read_exr(folder_ / "tall.exr").pixels, tall.pixels);
  // Half pixels, RLE (one row per block), the data window's corner at (-5, 7); tiles.
  const Image offset = parse_exr(corpus_file("exr_2x3_half_rle_offset_window"), "image.exr");
  ASSERT_EQ(offset.width, 2);
  ASSERT_EQ(offset.height, 3);
  EXPECT_EQ(offset.at(1, 2), Color(1.25, 1.0, 0.75));
  const Image tiled = parse_exr(corpus_file("exr_5x3_half_tiled_zip"), "image.exr");
  EXPECT_EQ(tiled.width, 5);
  EXPECT_EQ(tiled.height, 3);
}

// fuzz_readers: a 566-byte tiled image of 5 by 3 pixels with tiles of 9218 by 12034 made
// OpenEXR allocate 665 MB for one tile's decoding before reading it.
TEST(ParseExr, BlocksLargerThan64MiBAreRejected) {
  std::string bytes = corpus_file("exr_5x3_half_tiled_zip");
  const std::string tiles = std::string("tiles\0tiledesc\0", 15);
  const std::size_t at = bytes.find(tiles) + tiles.size() + 4;  // past the attribute's size
  const std::uint32_t size[2] = {9218, 12034};
  std::memcpy(bytes.data() + at, size, sizeof size);  // little-endian, as on the machines visproxy runs on
  EXPECT_EQ(exr_error(bytes), "image.exr: not a readable OpenEXR image: a block of 110929412 pixels needs " +
                                  std::to_string(110929412ull * (12 + 3 * 2)) +
                                  " bytes to decode, more than the 64 MiB allowed");
}

}  // namespace
}  // namespace visproxy
