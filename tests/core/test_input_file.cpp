// Files the user names (core/input_file.hpp): a regular file is read whole; a FIFO, a device or
// a directory is refused at once (a FIFO without a writer would block for ever, /dev/zero never
// end), and a file above the limit is refused as too large before anything is allocated.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/input_file.hpp"
#include "core/types.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

std::string refusal(const std::filesystem::path& path, std::uint64_t limit = UINT64_MAX) {
  try {
    read_input_file(path, "config file", limit);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

struct Scratch {
  std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("mpm_input_file_" + std::to_string(::getpid()));
  Scratch() {
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
  }
  ~Scratch() { std::filesystem::remove_all(dir); }
};

TEST(InputFile, ARegularFileIsReadWhole) {
  const Scratch s;
  std::string text(200000, 'a');
  text[12345] = '\0';  // binary content too
  std::ofstream(s.dir / "f.toml", std::ios::binary) << text;
  EXPECT_EQ(read_input_file(s.dir / "f.toml", "config file"), text);
  std::ofstream(s.dir / "empty.toml");
  EXPECT_EQ(read_input_file(s.dir / "empty.toml", "config file"), "");
}

TEST(InputFile, WhatIsNotARegularFileIsRefusedAtOnce) {
  const Scratch s;
  const auto fifo = s.dir / "run.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(refusal(fifo), "cannot read config file '" + fifo.string() +
                               "': it is a FIFO (named pipe), not a "
                               "regular file");
  EXPECT_EQ(refusal("/dev/zero"),
            "cannot read config file '/dev/zero': it is a character device, not a regular file");
  EXPECT_EQ(refusal(s.dir), "cannot read config file '" + s.dir.string() +
                                "': it is a directory, not a regular "
                                "file");
  EXPECT_EQ(refusal(s.dir / "missing.toml"), "cannot open config file '" +
                                                 (s.dir / "missing.toml").string() +
                                                 "': No such file or directory");
}

TEST(InputFile, AFileAboveTheLimitIsRefusedAsTooLarge) {
  const Scratch s;
  // 3 GiB without writing them: a sparse file.
  const auto big = s.dir / "big.toml";
  std::ofstream(big).close();
  std::filesystem::resize_file(big, std::uint64_t{3} << 30);
  const auto why = refusal(big, std::uint64_t{64} << 20);
  EXPECT_EQ(why, "config file '" + big.string() +
                     "' is too large: 3.0 GiB (3221225472 bytes), where a config file holds at "
                     "most 64.0 MiB");
  std::ofstream(s.dir / "small.toml") << "0123456789";
  EXPECT_EQ(refusal(s.dir / "small.toml", 10), "");
  EXPECT_NE(refusal(s.dir / "small.toml", 9).find("too large: 10 bytes"), std::string::npos);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
