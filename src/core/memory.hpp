#pragma once
// The resident memory of this process as the kernel records it (Linux /proc), for summary.json:
// what a run of a given size needs per process, measured rather than modelled.

namespace mpm {

// Starts a new record of the peak (Linux: writes 5 to /proc/self/clear_refs), so that the peak
// of a run is its own in a batch of runs in one process; false where that is not possible.
bool reset_peak_memory();

// The peak resident memory of this process since its start or the last reset_peak_memory
// [bytes] (Linux: VmHWM of /proc/self/status); negative where unknown.
double peak_memory_bytes();

}  // namespace mpm
