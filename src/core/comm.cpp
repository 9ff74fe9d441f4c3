#include "core/comm.hpp"

#include "core/comm_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#ifdef MPM_HAVE_MPI
#include <mpi.h>
#endif

namespace mpm {
namespace {

Comm g_world;
#ifdef MPM_HAVE_MPI
bool g_mpi_running = false;
// A duplicate of the world communicator for the reductions' point-to-point messages
// (tree_reduce), so that they can never match a message of an exchange.
MPI_Comm g_reduce = MPI_COMM_NULL;
#endif

// Started by an MPI launcher: Open MPI's mpirun sets OMPI_COMM_WORLD_SIZE, PMI and PMIx
// launchers (MPICH's hydra, srun) PMI_SIZE or PMIX_RANK.
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(v)) return true;
  return false;
}

#ifdef MPM_HAVE_MPI
void check_mpi(int rc, const char* what) {
  if (rc != MPI_SUCCESS) throw std::runtime_error(fmt::format("MPI error {} in {}", rc, what));
}
int to_int(std::size_t n) {
  if (n > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::runtime_error(fmt::format("an MPI message of {} bytes exceeds 2^31", n));
  return static_cast<int>(n);
}
#endif

}  // namespace

void Comm::init([[maybe_unused]] int* argc, [[maybe_unused]] char*** argv) {
  if (!launched_by_mpi()) return;
#ifdef MPM_HAVE_MPI
  int provided = 0;
  // Only the main thread calls MPI (OpenMP regions never do).
  check_mpi(MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  g_mpi_running = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &g_world.rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &g_world.size_);
  MPI_Comm local;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &local);
  MPI_Comm_size(local, &g_world.local_size_);
  MPI_Comm_free(&local);
  check_mpi(MPI_Comm_dup(MPI_COMM_WORLD, &g_reduce), "MPI_Comm_dup");
#else
  // A build without MPI started by mpirun: every process would run the whole problem alone.
  if (const char* n = std::getenv("OMPI_COMM_WORLD_SIZE"); n && std::atoi(n) > 1)
    throw InputError(
        "this mpm was built without MPI (CMake MPM_MPI=OFF or no MPI library found) but was "
        "started by mpirun with several processes; rebuild with libopenmpi-dev installed");
#endif
}

void Comm::finalize() {
#ifdef MPM_HAVE_MPI
  if (g_mpi_running) {
    int done = 0;
    MPI_Finalized(&done);
    if (!done) {
      if (g_reduce != MPI_COMM_NULL) MPI_Comm_free(&g_reduce);
      MPI_Finalize();
    }
    g_mpi_running = false;
  }
#endif
}

void Comm::abort([[maybe_unused]] int code) {
#ifdef MPM_HAVE_MPI
  if (g_mpi_running && g_world.size_ > 1) MPI_Abort(MPI_COMM_WORLD, code);
#endif
}

const Comm& Comm::world() {
  return g_world;
}

std::optional<Comm::Failure> Comm::agree(const Failure* mine) const {
  if (!distributed()) return mine ? std::optional<Failure>(*mine) : std::nullopt;
  // The lowest failing rank (size_ when none), then its code and message from it.
  const Index first = integer_reduce(mine ? rank_ : size_, Integer::Min);
  if (first == size_) return std::nullopt;
  const auto r = static_cast<int>(first);
  std::vector<std::byte> buf;
  if (rank_ == r) {
    const std::string text = fmt::format("{} {}", mine->exit_code, mine->message);
    buf.resize(text.size());
    std::memcpy(buf.data(), text.data(), text.size());
  }
  broadcast(buf, r);
  const std::string text(reinterpret_cast<const char*>(buf.data()), buf.size());
  const auto space = text.find(' ');
  Failure f;
  f.rank = r;
  f.exit_code = std::atoi(text.substr(0, space).c_str());
  f.message = space == std::string::npos ? std::string() : text.substr(space + 1);
  return f;
}

void Comm::check() const {
  if (!distributed()) return;
  if (const auto f = agree(nullptr))
    throw RemoteRunError(f->exit_code,
                         fmt::format("rank {} of {}: {}", f->rank, size_, f->message));
}

bool Comm::any(bool flag) const {
  if (!distributed()) return flag;
  return integer_reduce(flag ? 1 : 0, Integer::Max) != 0;
}

double Comm::sum(double v) const {
  sum(std::span<double>(&v, 1));
  return v;
}

Index Comm::sum(Index v) const {
  if (!distributed()) return v;
  return integer_reduce(v, Integer::Sum);
}

Index Comm::integer_reduce([[maybe_unused]] Index v, [[maybe_unused]] Integer op) const {
#ifdef MPM_HAVE_MPI
  // Integer sums and extrema are exact in any order, so MPI's own reduction gives the same value
  // on every rank and in every run.
  Index out = 0;
  const MPI_Op mpi_op = op == Integer::Sum ? MPI_SUM : op == Integer::Min ? MPI_MIN : MPI_MAX;
  check_mpi(MPI_Allreduce(&v, &out, 1, MPI_INT64_T, mpi_op, MPI_COMM_WORLD), "MPI_Allreduce");
  return out;
#else
  throw std::logic_error("Comm::integer_reduce in a build without MPI");
#endif
}

void Comm::tree_reduce([[maybe_unused]] std::span<double> v, [[maybe_unused]] bool max) const {
#ifdef MPM_HAVE_MPI
  // Recursive doubling on a fixed tree. With N = P + E ranks, P the largest power of two <= N:
  // rank P + r (r < E) first hands its values to rank r, which combines v_r op v_(P+r); then in
  // rounds k = 1, 2, 4, ... < P ranks r and r xor k swap their results and both combine them
  // lower rank first, (a op b) with a from the lower one, so both hold the same bits and every
  // rank ends with ((v_0 op v_1) op (v_2 op v_3)) op ..., bracketed by N alone; rank r then
  // returns the result to P + r. log2(P) message latencies (two more when N is not a power of
  // two) of n values each, where an all-gather moves N n values to every rank.
  // max: NaN wins (a NaN on any rank must stop the run, whatever the order).
  const int n = to_int(v.size());
  std::vector<double> other(v.size());
  const auto combine = [&](const double* a, const double* b) {
    for (std::size_t i = 0; i < v.size(); ++i) {
      const double x = a[i], y = b[i];
      v[i] = !max ? x + y : (std::isnan(x) || x >= y) ? x : y;
    }
  };
  int P = 1;
  while (2 * P <= size_) P *= 2;
  const int extra = size_ - P;
  if (rank_ >= P) {
    check_mpi(MPI_Send(v.data(), n, MPI_DOUBLE, rank_ - P, 0, g_reduce), "MPI_Send");
    check_mpi(MPI_Recv(v.data(), n, MPI_DOUBLE, rank_ - P, 1, g_reduce, MPI_STATUS_IGNORE),
              "MPI_Recv");
    return;
  }
  std::vector<double> mine(v.size());
  if (rank_ < extra) {
    check_mpi(MPI_Recv(other.data(), n, MPI_DOUBLE, rank_ + P, 0, g_reduce, MPI_STATUS_IGNORE),
              "MPI_Recv");
    std::copy(v.begin(), v.end(), mine.begin());
    combine(mine.data(), other.data());
  }
  for (int k = 1; k < P; k *= 2) {
    const int partner = rank_ ^ k;
    std::copy(v.begin(), v.end(), mine.begin());
    check_mpi(MPI_Sendrecv(mine.data(), n, MPI_DOUBLE, partner, 2, other.data(), n, MPI_DOUBLE,
                           partner, 2, g_reduce, MPI_STATUS_IGNORE),
              "MPI_Sendrecv");
    if (rank_ < partner)
      combine(mine.data(), other.data());
    else
      combine(other.data(), mine.data());
  }
  if (rank_ < extra)
    check_mpi(MPI_Send(v.data(), n, MPI_DOUBLE, rank_ + P, 1, g_reduce), "MPI_Send");
#else
  throw std::logic_error("Comm::tree_reduce in a build without MPI");
#endif
}

void Comm::sum(std::span<double> v) const {
  if (!distributed() || v.empty()) return;
  tree_reduce(v, false);
}

double Comm::max(double v) const {
  if (!distributed()) return v;
  tree_reduce(std::span<double>(&v, 1), true);
  return v;
}

double Comm::min(double v) const {
  return -max(-v);
}

namespace {
// Every rank's values, rank after rank, as raw bytes (Index and double: 8 bytes each, the same
// representation on every process of a run).
template <class T>
std::vector<T> allgather_values(std::span<const T> mine, int size, bool distributed) {
  static_assert(sizeof(T) == 8);
  std::vector<T> out(mine.size() * static_cast<std::size_t>(size));
  if (!distributed) {
    std::copy(mine.begin(), mine.end(), out.begin());
    return out;
  }
#ifdef MPM_HAVE_MPI
  const int n = to_int(mine.size() * sizeof(T));
  check_mpi(MPI_Allgather(mine.data(), n, MPI_BYTE, out.data(), n, MPI_BYTE, MPI_COMM_WORLD),
            "MPI_Allgather");
#endif
  return out;
}
}  // namespace

std::vector<Index> Comm::allgather(std::span<const Index> mine) const {
  return allgather_values(mine, size_, distributed());
}

std::vector<double> Comm::allgather(std::span<const double> mine) const {
  return allgather_values(mine, size_, distributed());
}

std::vector<std::vector<std::byte>> Comm::gather(const std::vector<std::byte>& mine,
                                                 [[maybe_unused]] int root) const {
  std::vector<std::vector<std::byte>> out;
  if (!distributed()) {
    out.push_back(mine);
    return out;
  }
#ifdef MPM_HAVE_MPI
  const Index n = static_cast<Index>(mine.size());
  const auto counts = allgather(std::span<const Index>(&n, 1));
  std::vector<int> c(static_cast<std::size_t>(size_)), displ(static_cast<std::size_t>(size_));
  std::size_t total = 0;
  for (int r = 0; r < size_; ++r) {
    c[static_cast<std::size_t>(r)] =
        to_int(static_cast<std::size_t>(counts[static_cast<std::size_t>(r)]));
    displ[static_cast<std::size_t>(r)] = to_int(total);
    total += static_cast<std::size_t>(counts[static_cast<std::size_t>(r)]);
  }
  std::vector<std::byte> all(rank_ == root ? total : 0);
  check_mpi(MPI_Gatherv(mine.data(), to_int(mine.size()), MPI_BYTE, all.data(), c.data(),
                        displ.data(), MPI_BYTE, root, MPI_COMM_WORLD),
            "MPI_Gatherv");
  if (rank_ == root) {
    out.resize(static_cast<std::size_t>(size_));
    for (int r = 0; r < size_; ++r) {
      const auto b = all.begin() + displ[static_cast<std::size_t>(r)];
      out[static_cast<std::size_t>(r)].assign(b, b + c[static_cast<std::size_t>(r)]);
    }
  }
#endif
  return out;
}

void Comm::broadcast([[maybe_unused]] std::vector<std::byte>& buf,
                     [[maybe_unused]] int root) const {
  if (!distributed()) return;
#ifdef MPM_HAVE_MPI
  Index n = static_cast<Index>(buf.size());
  check_mpi(MPI_Bcast(&n, 1, MPI_INT64_T, root, MPI_COMM_WORLD), "MPI_Bcast");
  buf.resize(static_cast<std::size_t>(n));
  check_mpi(MPI_Bcast(buf.data(), to_int(buf.size()), MPI_BYTE, root, MPI_COMM_WORLD), "MPI_Bcast");
#endif
}

std::vector<std::vector<std::byte>> Comm::alltoall(
    const std::vector<std::vector<std::byte>>& send) const {
  std::vector<std::vector<std::byte>> recv(static_cast<std::size_t>(size_));
  if (!distributed()) {
    recv[0] = send.at(0);
    return recv;
  }
#ifdef MPM_HAVE_MPI
  const auto n = static_cast<std::size_t>(size_);
  std::vector<int> sc(n), rc(n), sd(n), rd(n);
  std::size_t st = 0;
  for (std::size_t r = 0; r < n; ++r) {
    sc[r] = to_int(send[r].size());
    sd[r] = to_int(st);
    st += send[r].size();
  }
  check_mpi(MPI_Alltoall(sc.data(), 1, MPI_INT, rc.data(), 1, MPI_INT, MPI_COMM_WORLD),
            "MPI_Alltoall");
  std::size_t rt = 0;
  for (std::size_t r = 0; r < n; ++r) {
    rd[r] = to_int(rt);
    rt += static_cast<std::size_t>(rc[r]);
  }
  std::vector<std::byte> sb(st), rb(rt);
  for (std::size_t r = 0; r < n; ++r) std::copy(send[r].begin(), send[r].end(), sb.begin() + sd[r]);
  check_mpi(MPI_Alltoallv(sb.data(), sc.data(), sd.data(), MPI_BYTE, rb.data(), rc.data(),
                          rd.data(), MPI_BYTE, MPI_COMM_WORLD),
            "MPI_Alltoallv");
  for (std::size_t r = 0; r < n; ++r)
    recv[r].assign(rb.begin() + rd[r], rb.begin() + rd[r] + rc[r]);
#endif
  return recv;
}

std::vector<std::vector<std::byte>> Comm::exchange(
    const std::vector<int>& peers, [[maybe_unused]] const std::vector<std::vector<std::byte>>& send,
    [[maybe_unused]] int tag) const {
  std::vector<std::vector<std::byte>> recv(peers.size());
  if (peers.empty()) return recv;
#ifdef MPM_HAVE_MPI
  // Sizes first, then the data: every request completes before the buffers go out of scope.
  const std::size_t n = peers.size();
  std::vector<Index> out_size(n), in_size(n);
  std::vector<MPI_Request> req(2 * n);
  for (std::size_t k = 0; k < n; ++k) {
    out_size[k] = static_cast<Index>(send[k].size());
    MPI_Irecv(&in_size[k], 1, MPI_INT64_T, peers[k], tag, MPI_COMM_WORLD, &req[k]);
    MPI_Isend(&out_size[k], 1, MPI_INT64_T, peers[k], tag, MPI_COMM_WORLD, &req[n + k]);
  }
  check_mpi(MPI_Waitall(to_int(2 * n), req.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
  for (std::size_t k = 0; k < n; ++k) {
    recv[k].resize(static_cast<std::size_t>(in_size[k]));
    MPI_Irecv(recv[k].data(), to_int(recv[k].size()), MPI_BYTE, peers[k], tag + 1, MPI_COMM_WORLD,
              &req[k]);
    MPI_Isend(send[k].data(), to_int(send[k].size()), MPI_BYTE, peers[k], tag + 1, MPI_COMM_WORLD,
              &req[n + k]);
  }
  check_mpi(MPI_Waitall(to_int(2 * n), req.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
#else
  throw std::logic_error("Comm::exchange with peers in a build without MPI");
#endif
  return recv;
}

#ifdef MPM_HAVE_MPI
namespace {
// The first MPI-IO error of a rank, as a failure naming the path (nothing when rc is success).
void note_file_error(int rc, const char* what, const std::string& path, int rank,
                     std::optional<Comm::Failure>& failed) {
  if (rc == MPI_SUCCESS || failed) return;
  char text[MPI_MAX_ERROR_STRING];
  int len = 0;
  MPI_Error_string(rc, text, &len);
  failed = Comm::Failure{rank, exit_code::kOutput,
                         fmt::format("cannot write '{}': {}: {}", path, what,
                                     std::string(text, static_cast<std::size_t>(len)))};
}
static_assert(sizeof(MPI_File) == sizeof(void*));
}  // namespace
#endif

OrderedFile::OrderedFile(const Comm& comm, std::string path, std::string shown)
    : comm_(comm), path_(std::move(path)), shown_(shown.empty() ? path_ : std::move(shown)) {
  if (!comm_.distributed())
    throw std::logic_error("OrderedFile: a run on one process writes its files itself");
#ifdef MPM_HAVE_MPI
  MPI_File fh = MPI_FILE_NULL;
  note_file_error(MPI_File_open(MPI_COMM_WORLD, path_.c_str(), MPI_MODE_CREATE | MPI_MODE_WRONLY,
                                MPI_INFO_NULL, &fh),
                  "MPI_File_open", shown_, comm_.rank(), failed_);
  // (Every rank learns whether all opened it before the collective calls on the file.)
  if (comm_.any(failed_.has_value())) {
    if (!failed_)
      failed_ = Comm::Failure{
          comm_.rank(), exit_code::kOutput,
          fmt::format("cannot write '{}': another process could not open it", shown_)};
    return;
  }
  std::memcpy(&file_, &fh, sizeof fh);
  open_ = true;
  note_file_error(MPI_File_set_size(fh, 0), "MPI_File_set_size", shown_, comm_.rank(), failed_);
#endif
}

void OrderedFile::append([[maybe_unused]] std::string_view mine) {
  if (!open_) return;  // (on every rank alike)
#ifdef MPM_HAVE_MPI
  MPI_File fh;
  std::memcpy(&fh, &file_, sizeof fh);
  // Rank r writes after the sizes of ranks 0 .. r - 1 of this round.
  const std::uint64_t size = failed_ ? 0 : mine.size();
  std::uint64_t offset = 0, round = 0;
  check_mpi(MPI_Exscan(&size, &offset, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD), "MPI_Exscan");
  if (comm_.rank() == 0) offset = 0;  // (MPI_Exscan leaves rank 0's undefined)
  check_mpi(MPI_Allreduce(&size, &round, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD),
            "MPI_Allreduce");
  constexpr std::uint64_t kChunk = std::uint64_t{1} << 30;
  const auto chunks = static_cast<double>((size + kChunk - 1) / kChunk);
  const auto writes = static_cast<std::uint64_t>(comm_.max(chunks));  // (exact)
  for (std::uint64_t k = 0; k < writes; ++k) {
    const std::uint64_t at = k * kChunk;
    const std::uint64_t n = at >= size ? 0 : std::min(kChunk, size - at);
    MPI_Status status;
    const int rc = MPI_File_write_at_all(fh, static_cast<MPI_Offset>(written_ + offset + at),
                                         n > 0 ? mine.data() + at : nullptr, static_cast<int>(n),
                                         MPI_BYTE, &status);
    note_file_error(rc, "MPI_File_write_at_all", shown_, comm_.rank(), failed_);
    // A short write (a full disk, a file-size limit) is no error to MPI-IO: its count says so.
    int count = 0;
    if (rc == MPI_SUCCESS && !failed_ &&
        (MPI_Get_count(&status, MPI_BYTE, &count) != MPI_SUCCESS ||
         static_cast<std::uint64_t>(count) != n))
      failed_ = Comm::Failure{
          comm_.rank(), exit_code::kOutput,
          fmt::format("cannot write '{}': MPI_File_write_at_all wrote {} of {} bytes at offset {} "
                      "(a full disk or a file-size limit)",
                      shown_, count, n, written_ + offset + at)};
  }
  written_ += round;
#endif
}

std::optional<Comm::Failure> OrderedFile::close() {
#ifdef MPM_HAVE_MPI
  if (open_) {
    MPI_File fh;
    std::memcpy(&fh, &file_, sizeof fh);
    note_file_error(MPI_File_sync(fh), "MPI_File_sync", shown_, comm_.rank(), failed_);
    note_file_error(MPI_File_close(&fh), "MPI_File_close", shown_, comm_.rank(), failed_);
    open_ = false;
  }
#endif
  return comm_.agree(failed_ ? &*failed_ : nullptr);
}

}  // namespace mpm
