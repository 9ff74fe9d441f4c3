#pragma once
// Reading a file the user named (a configuration, a batch file, a mesh, a checkpoint): only a
// regular file is read. A FIFO, a device, a socket or a directory given by mistake is refused
// at once instead of blocking for ever (a FIFO without a writer) or reading without end
// (/dev/zero); a file larger than `max_bytes` is refused as too large for what it should be,
// before anything is allocated.
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <string_view>

namespace mpm {

// The bytes of the regular file at `path`. `what` names the file in messages ("config file",
// "mesh file"). InputError naming the path: missing or unreadable (the system's reason), not a
// regular file (what it is instead), larger than max_bytes (its size and the limit), or a read
// that failed.
std::string read_input_file(const std::filesystem::path& path, std::string_view what,
                            std::uint64_t max_bytes = std::numeric_limits<std::uint64_t>::max());

// "a directory", "a FIFO (named pipe)", "a character device", ... for the file type bits of
// st_mode; "a regular file" for one.
std::string_view file_type_name(unsigned mode);

// A size in bytes as people read it: "512 bytes", "3.2 MiB", "3.0 GiB".
std::string byte_size_text(std::uint64_t bytes);

}  // namespace mpm
