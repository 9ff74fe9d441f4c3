#include "core/input_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/types.hpp"

namespace mpm {

std::string_view file_type_name(unsigned mode) {
  switch (mode & S_IFMT) {
    case S_IFREG:
      return "a regular file";
    case S_IFDIR:
      return "a directory";
    case S_IFIFO:
      return "a FIFO (named pipe)";
    case S_IFCHR:
      return "a character device";
    case S_IFBLK:
      return "a block device";
    case S_IFSOCK:
      return "a socket";
    case S_IFLNK:
      return "a symbolic link";
    default:
      return "not a regular file";
  }
}

std::string byte_size_text(std::uint64_t bytes) {
  if (bytes < 1024) return fmt::format("{} bytes", bytes);
  const double b = static_cast<double>(bytes);
  if (bytes < (std::uint64_t{1} << 20)) return fmt::format("{:.1f} KiB", b / 1024.0);
  if (bytes < (std::uint64_t{1} << 30)) return fmt::format("{:.1f} MiB", b / 1048576.0);
  return fmt::format("{:.1f} GiB", b / 1073741824.0);
}

std::string read_input_file(const std::filesystem::path& path, std::string_view what,
                            std::uint64_t max_bytes) {
  // O_NONBLOCK: opening a FIFO without a writer returns at once instead of waiting for one; the
  // type is then checked on the open descriptor (no race with a file swapped after a stat).
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    throw InputError(
        fmt::format("cannot open {} '{}': {}", what, path.string(), std::strerror(err)));
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    throw InputError(
        fmt::format("cannot read {} '{}': {}", what, path.string(), std::strerror(err)));
  }
  if (!S_ISREG(st.st_mode))
    throw InputError(fmt::format("cannot read {} '{}': it is {}, not a regular file", what,
                                 path.string(), file_type_name(st.st_mode)));
  const auto size = static_cast<std::uint64_t>(st.st_size);
  if (size > max_bytes)
    throw InputError(fmt::format("{} '{}' is too large: {} ({} bytes), where a {} holds at most {}",
                                 what, path.string(), byte_size_text(size), size, what,
                                 byte_size_text(max_bytes)));
  // Blocking reads from here (a regular file never blocks, but the flag is cleared for clarity).
  (void)::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  std::string bytes(static_cast<std::size_t>(size), '\0');
  std::size_t got = 0;
  char more[65536];
  while (true) {
    // The size fstat gave first, then (a file that grew since) in chunks, within the limit.
    char* into = got < bytes.size() ? bytes.data() + got : more;
    const std::size_t room = got < bytes.size() ? bytes.size() - got : sizeof more;
    const ssize_t n = ::read(fd, into, room);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      throw InputError(
          fmt::format("cannot read {} '{}': {}", what, path.string(), std::strerror(err)));
    }
    if (n == 0) break;
    if (into == more) {
      if (bytes.size() + static_cast<std::size_t>(n) > max_bytes)
        throw InputError(fmt::format("{} '{}' is too large: it grew past {} while read", what,
                                     path.string(), byte_size_text(max_bytes)));
      bytes.append(more, static_cast<std::size_t>(n));
    }
    got += static_cast<std::size_t>(n);
  }
  bytes.resize(got);  // (a file that shrank since fstat)
  return bytes;
}

}  // namespace mpm
