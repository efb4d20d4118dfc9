#include "visproxy/core/files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <system_error>
#include <utility>

#include "visproxy/core/errors.h"

namespace visproxy {
namespace {

std::string errno_text() { return std::strerror(errno); }

// Closes a POSIX file descriptor on scope exit.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const { return fd_; }
  int release() { return std::exchange(fd_, -1); }

 private:
  int fd_;
};

}  // namespace

std::string read_file(const std::filesystem::path& path) {
  FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) throw IOError(path, "cannot open: " + errno_text());
  struct stat info {};
  if (::fstat(fd.get(), &info) != 0) throw IOError(path, "cannot stat: " + errno_text());
  if (!S_ISREG(info.st_mode)) throw IOError(path, "not a regular file");

  std::string bytes(static_cast<std::size_t>(info.st_size), '\0');
  std::size_t filled = 0;
  while (filled < bytes.size()) {
    const ssize_t got = ::read(fd.get(), bytes.data() + filled, bytes.size() - filled);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw IOError(path, "cannot read: " + errno_text());
    if (got == 0) break;  // the file shrank while we read it
    filled += static_cast<std::size_t>(got);
  }
  bytes.resize(filled);
  return bytes;
}

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes) {
  const std::filesystem::path folder = path.has_parent_path() ? path.parent_path() : ".";
  std::string pattern = (folder / ("." + path.filename().string() + ".tmp-XXXXXX")).string();
  FileDescriptor fd(::mkstemp(pattern.data()));
  if (fd.get() < 0) throw IOError(path, "cannot create a temporary file beside it: " + errno_text());
  const std::filesystem::path temporary = pattern;

  auto fail = [&](const std::string& problem) {
    ::close(fd.release());
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw IOError(path, problem);
  };

  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t put = ::write(fd.get(), bytes.data() + written, bytes.size() - written);
    if (put < 0 && errno == EINTR) continue;
    if (put < 0) fail("cannot write: " + errno_text());
    written += static_cast<std::size_t>(put);
  }
  if (::fchmod(fd.get(), 0644) != 0) fail("cannot set permissions: " + errno_text());
  if (::fsync(fd.get()) != 0) fail("cannot flush to disk: " + errno_text());
  if (::close(fd.release()) != 0) fail("cannot close: " + errno_text());
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    const std::string problem = "cannot rename the temporary file into place: " + errno_text();
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw IOError(path, problem);
  }
}

}  // namespace visproxy
