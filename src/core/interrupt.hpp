#pragma once
// Ending a run cleanly on SIGINT, SIGTERM, SIGHUP, SIGUSR1 or SIGUSR2 (README, "Exit codes"): the
// first signal only sets a flag, which the time loop reads after each step (driver/driver.hpp,
// TimeLoop): it then writes the state of that step (history row, frame, checkpoint if checkpoints
// are on) and summary.json with "status": "interrupted", and the run exits with
// exit_code::kInterrupted. A second signal ends the process at once with the default action.
namespace mpm {

// Installs the handlers (once per process; `mpm run` and `mpm study` do).
void install_interrupt_handlers();

// The signal received since the handlers were installed, or 0.
int interrupt_signal();

// "SIGINT", "SIGTERM", "SIGHUP", "SIGUSR1", "SIGUSR2" (else "a signal").
const char* signal_name(int sig);

// Clears the flag (tests).
void clear_interrupt();

}  // namespace mpm
