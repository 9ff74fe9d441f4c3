#pragma once
// Collective file output of a distributed run through MPI-IO, the standard engine for
// it: one file whose parts the processes write at once, each at its offset, so that no process
// gathers what the others write (a CSV frame of the whole body: driver/driver.cpp). Declared
// apart from core/comm.hpp (which the whole tree includes); implemented in core/comm.cpp, the
// only file that includes <mpi.h>.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "core/comm.hpp"

namespace mpm {

// One file written by all the processes of a distributed comm, in rounds: each append() puts
// every rank's bytes after what the earlier rounds wrote, rank after rank, so a writer can
// stream a file larger than any process's memory. A failing MPI-IO call is recorded (the first
// one, naming the path) and the calls that follow write nothing, so every rank still makes the
// same collective calls; close() agrees the failure of the lowest rank over all of them.
// Every member is collective. Without MPI (or on one process) the constructor throws
// std::logic_error: one process writes its files itself.
class OrderedFile {
 public:
  // Creates or truncates the file at `path`. (A failed open on some ranks is agreed at once;
  // those ranks then write nothing, the others leave the file open: a handle lost by a failing
  // run, rather than a collective close that waits for ranks that have none.)
  // `shown` names the file in messages (the name it will have: it may be written under a
  // temporary one); empty: path.
  OrderedFile(const Comm& comm, std::string path, std::string shown = {});
  OrderedFile(const OrderedFile&) = delete;
  OrderedFile& operator=(const OrderedFile&) = delete;
  // Not closed (an exception between the rounds): the handle is left open, for the same reason.
  ~OrderedFile() = default;

  // Rank r's `mine` at the end of the file plus the sizes of ranks 0 .. r - 1 of this round (in
  // writes of at most 1 GiB).
  void append(std::string_view mine);
  // Flushes the file to the disk (MPI_File_sync) and closes it. The failure of the lowest rank
  // that met one in any call (exit_code::kOutput, the system's text), the same on every rank, or
  // nothing.
  std::optional<Comm::Failure> close();

 private:
  const Comm& comm_;
  std::string path_, shown_;
  void* file_ = nullptr;  // the MPI_File (an opaque pointer in Open MPI and MPICH)
  bool open_ = false;
  std::uint64_t written_ = 0;  // bytes of all ranks so far
  std::optional<Comm::Failure> failed_;
};

}  // namespace mpm
