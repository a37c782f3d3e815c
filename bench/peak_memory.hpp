// Peak memory of one task, measured in a fresh process.
//
// Inside one process the peak resident set (VmHWM) only grows, and freed memory that malloc keeps
// is reused without showing, so the harness measures each task in a child of its own: the bench
// binary runs again as `hybridtree_bench --peak-child NAME ARG`. The child prepares its inputs
// (untimed, unmeasured), returns what malloc holds free to the system (malloc_trim), resets its
// high-water mark (`echo 5 > /proc/self/clear_refs`, Linux 4.0 and later), reads VmRSS, runs the
// task once and reads VmHWM: the peak is VmHWM - VmRSS, the memory the task itself needed at its
// peak, output included. A fresh exec (not a bare fork) keeps TBB's worker threads sound.
#pragma once

#include <functional>
#include <optional>
#include <string>

namespace ht::bench {

/// A named task: given its argument, prepares the inputs and returns the work to measure.
using PeakTask = std::function<std::function<void()>(const std::string& arg)>;

/// Registers a task under `name` (at static initialization); returns true.
bool register_peak_task(const std::string& name, PeakTask task);

/// Runs task `name` with `arg` in a child process; its peak in bytes, or nothing when the child
/// failed or the high-water mark cannot be reset on this system.
std::optional<double> peak_bytes_in_child(const std::string& name, const std::string& arg);

/// The child's side (bench/main.cpp calls it for --peak-child): prints "peak_bytes N" on stdout;
/// returns the exit code.
int peak_child_main(const std::string& name, const std::string& arg);

}  // namespace ht::bench
