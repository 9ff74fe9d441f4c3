#include "core/interrupt.hpp"

#include <atomic>
#include <csignal>

namespace mpm {
namespace {

// Lock-free, hence async-signal-safe to store from the handler.
std::atomic<int> g_signal{0};
static_assert(std::atomic<int>::is_always_lock_free);

extern "C" void on_interrupt(int sig) {
  if (g_signal.exchange(sig) != 0) {
    // The second signal: the default action (termination) at once.
    std::signal(sig, SIG_DFL);
    std::raise(sig);
  }
}

}  // namespace

void install_interrupt_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;  // writes in progress go on instead of failing with EINTR
  // SIGUSR1 and SIGUSR2 too: Open MPI's mpirun forwards them to every process (it answers
  // SIGINT and SIGTERM by ending the job itself, with its own exit code 1), and batch systems
  // send them ahead of a time limit (Slurm's --signal).
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGUSR1, SIGUSR2}) sigaction(sig, &sa, nullptr);
}

int interrupt_signal() {
  return g_signal.load(std::memory_order_relaxed);
}

const char* signal_name(int sig) {
  switch (sig) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    case SIGUSR1:
      return "SIGUSR1";
    case SIGUSR2:
      return "SIGUSR2";
    default:
      return "a signal";
  }
}

void clear_interrupt() {
  g_signal.store(0);
}

}  // namespace mpm
