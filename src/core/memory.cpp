#include "core/memory.hpp"

#include <fstream>
#include <sstream>
#include <string>

namespace mpm {

bool reset_peak_memory() {
  std::ofstream f("/proc/self/clear_refs");
  if (!f) return false;
  f << "5";
  f.flush();
  return static_cast<bool>(f);
}

double peak_memory_bytes() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) {
      std::istringstream in(line.substr(6));
      double kb = -1.0;
      in >> kb;  // "VmHWM:    123456 kB"
      return kb >= 0.0 ? kb * 1024.0 : -1.0;
    }
  return -1.0;
}

}  // namespace mpm
