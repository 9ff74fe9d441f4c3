#pragma once
// The processes of a distributed run: MPI's world communicator when `mpm` was started
// by an MPI launcher (mpirun) and built with MPI (CMake MPM_MPI), else one process. Only
// core/comm.cpp includes <mpi.h>; everything above sees this interface, whose operations are
// plain copies with one process.
//
// Every reduction is deterministic: sums and maxima of doubles are combined by recursive doubling
// on a fixed tree over the ranks (Comm::tree_reduce), bracketed by the number of ranks alone, so a
// run gives the same bits every time with the same number of ranks, and every rank gets the same
// bits (MPI_Allreduce promises neither for doubles); integer sums and extrema, exact in any
// order, use MPI_Allreduce. Both take about log2(N) message latencies and move n values per
// round, where an all-gather moves N n values to every rank (BENCHMARKS.md, the communication
// model of distributed runs).
//
// Failures: a rank that meets a RunError must not leave the others waiting in a collective
// operation. Every collective operation of a time step therefore starts with agree(): each rank
// says whether it has failed, and when one has, every rank learns the failure of the lowest
// failing rank (its exit code and message) and stops (Comm::check throws it as a RunError).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace mpm {

// A RunError raised by agree() for a failure detected on another rank: the rank that catches it
// has nothing to report to the others (they know already).
class RemoteRunError : public RunError {
 public:
  using RunError::RunError;
};

class Comm {
 public:
  // MPI_Init when this process was started by an MPI launcher (the environment of Open MPI's
  // mpirun, or of a PMI/PMIx launcher such as srun), else nothing: a plain `mpm` never starts
  // MPI's run-time. Once, before any other call; finalize() at exit.
  static void init(int* argc, char*** argv);
  static void finalize();
  // Ends every process of the run with `code` (MPI_Abort): for errors that only one process
  // meets outside the agreed points (an internal error), which would leave the others waiting.
  // Returns when the run has one process.
  static void abort(int code);
  // The processes of this run (one when MPI is not running).
  static const Comm& world();

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool distributed() const { return size_ > 1; }
  bool root() const { return rank_ == 0; }
  // Ranks on this rank's machine (OpenMP threads are shared among them).
  int local_size() const { return local_size_; }

  struct Failure {
    int rank = -1;
    int exit_code = 0;
    std::string message;
  };
  // Collective: each rank passes its own failure or nothing; returns the failure of the lowest
  // failing rank, or nothing when none failed.
  std::optional<Failure> agree(const Failure* mine) const;
  // agree(nullptr), throwing the failure of another rank as a RemoteRunError naming the rank.
  void check() const;
  // Collective: whether `flag` holds on any rank.
  bool any(bool flag) const;

  // Collective sums and extrema over the ranks (the fixed tree for doubles; max: NaN if any
  // rank has one).
  double sum(double v) const;
  Index sum(Index v) const;
  void sum(std::span<double> v) const;  // elementwise, in place
  double max(double v) const;
  double min(double v) const;
  // Collective: every rank's n values, rank after rank (n the same on every rank).
  std::vector<Index> allgather(std::span<const Index> mine) const;
  std::vector<double> allgather(std::span<const double> mine) const;
  // Collective: the byte buffers of every rank at `root` (in rank order; empty elsewhere).
  std::vector<std::vector<std::byte>> gather(const std::vector<std::byte>& mine, int root) const;
  // Collective: root's buffer on every rank.
  void broadcast(std::vector<std::byte>& buf, int root) const;
  // Collective: send[r] to rank r; returns what each rank sent to this one (index: source).
  // Ranks with nothing to say to each other exchange only the counts.
  std::vector<std::vector<std::byte>> alltoall(
      const std::vector<std::vector<std::byte>>& send) const;
  // Point-to-point with known partners (a halo exchange): send[k] to peers[k] and receive from
  // each peer what it sends; the peers must send to this rank too. Returns the received buffers
  // in the order of peers. tag: distinguishes the exchanges of one step.
  std::vector<std::vector<std::byte>> exchange(const std::vector<int>& peers,
                                               const std::vector<std::vector<std::byte>>& send,
                                               int tag) const;

 private:
  enum class Integer { Sum, Min, Max };
  // MPI_Allreduce of one integer (exact in any order).
  Index integer_reduce(Index v, Integer op) const;
  // v combined elementwise over the ranks on the fixed tree (sum, or max with NaN winning), the
  // same bits on every rank.
  void tree_reduce(std::span<double> v, bool max) const;

  int rank_ = 0, size_ = 1, local_size_ = 1;
};

}  // namespace mpm
