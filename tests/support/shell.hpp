#pragma once
// Shell commands for the tests of the command line: the exit code and the output, stdout and
// stderr together.
#include <fmt/format.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace mpm::test {

struct ShellResult {
  int code;         // the exit code; -1 when the command did not exit (a signal)
  std::string out;  // stdout and stderr together
};

// `command` run by /bin/sh; with seconds > 0 under timeout(1), so that a command that blocks
// fails with exit code 124 instead of hanging the suite.
inline ShellResult shell(const std::string& command, int seconds = 0) {
  std::string cmd = command + " 2>&1";
  if (seconds > 0) {
    std::string quoted;
    for (char c : command) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    cmd = fmt::format("timeout {} sh -c '{}' 2>&1", seconds, quoted);
  }
  FILE* f = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf{};
  while (std::size_t n = fread(buf.data(), 1, buf.size(), f)) out.append(buf.data(), n);
  const int status = pclose(f);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace mpm::test
