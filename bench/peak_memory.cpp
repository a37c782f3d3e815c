#include "bench/peak_memory.hpp"

#include <malloc.h>
#include <unistd.h>

#include <cstdio>
#include <exception>
#include <fstream>
#include <map>
#include <sstream>

namespace ht::bench {
namespace {

std::map<std::string, PeakTask>& tasks() {
  static std::map<std::string, PeakTask> registry;
  return registry;
}

/// A "Vm...:  N kB" line of /proc/self/status, in bytes; -1 when missing.
double status_bytes(const std::string& key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key + ":", 0) != 0) continue;
    std::istringstream fields(line.substr(key.size() + 1));
    double kb = -1;
    fields >> kb;
    return kb * 1024.0;
  }
  return -1;
}

}  // namespace

bool register_peak_task(const std::string& name, PeakTask task) {
  tasks()[name] = std::move(task);
  return true;
}

int peak_child_main(const std::string& name, const std::string& arg) {
  const auto it = tasks().find(name);
  if (it == tasks().end()) {
    std::fprintf(stderr, "--peak-child: no task named %s\n", name.c_str());
    return 2;
  }
  try {
    const std::function<void()> work = it->second(arg);
    malloc_trim(0);
    {
      std::ofstream reset("/proc/self/clear_refs");
      reset << "5";
      reset.flush();
      if (!reset) {
        std::fprintf(stderr, "--peak-child: cannot reset the high-water mark (/proc/self/clear_refs)\n");
        return 1;
      }
    }
    const double before = status_bytes("VmRSS");
    work();
    const double peak = status_bytes("VmHWM");
    if (before < 0 || peak < 0) return 1;
    std::printf("peak_bytes %.0f\n", peak - before);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "--peak-child %s %s: %s\n", name.c_str(), arg.c_str(), e.what());
    return 1;
  }
}

std::optional<double> peak_bytes_in_child(const std::string& name, const std::string& arg) {
  char exe[4096];
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n <= 0) return std::nullopt;
  exe[n] = '\0';
  // Names and arguments are the harness's own tokens (letters, digits, ':', '.'), no quoting needed.
  std::string command = "'";
  command.append(exe).append("' --peak-child ").append(name).append(" ").append(arg);
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return std::nullopt;
  double bytes = -1;
  char line[256];
  while (std::fgets(line, sizeof line, pipe) != nullptr) std::sscanf(line, "peak_bytes %lf", &bytes);
  if (pclose(pipe) != 0 || bytes < 0) return std::nullopt;
  return bytes;
}

}  // namespace ht::bench
