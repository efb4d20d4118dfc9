#pragma once
// Whole-file reads and crash-safe writes.

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace visproxy {

/// Reads a whole regular file into memory.
/// Throws IOError when the path does not exist, is not a regular file or cannot be read.
std::string read_file(const std::filesystem::path& path);

/// Writes `bytes` to `path` so that readers never see a partial file: the bytes go to a
/// temporary file in the same folder, which is flushed to disk and then renamed over
/// `path`. On failure the temporary file is removed, `path` is left as it was, and
/// IOError is thrown.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace visproxy
