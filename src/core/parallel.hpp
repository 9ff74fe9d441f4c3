#pragma once
// OpenMP helpers of the explicit core. Results must not depend on the thread count, so every
// sum that crosses particles runs over a FIXED partition of the particles into chunks (the
// partition depends only on the particle count), each chunk summed in particle order and the
// chunk results combined in chunk order. One thread and many threads then give the same bits.
//
// The particle-to-grid scatters (GridAccumulator) give each chunk its own slice of grid
// buffer covering only the DOFs its particles touch (particles are seeded cell by cell, so a
// chunk touches a narrow band of the grid), then add the slices into the grid in chunk order.
// No locks or atomics; the extra work is zeroing and adding the slices, about one grid's worth
// plus the stencil overlap between chunks per scatter.
#include <omp.h>
#include <algorithm>
#include <array>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "core/dof_array.hpp"
#include "core/types.hpp"

namespace mpm {

// Sets this thread's OpenMP thread count for a scope and restores the previous count when it
// ends (driver/run.cpp sizes a run's threads with it; the thread-count tests use it too).
class ScopedThreads {
 public:
  explicit ScopedThreads(int n) : saved_(omp_get_max_threads()) { omp_set_num_threads(n); }
  ~ScopedThreads() { omp_set_num_threads(saved_); }
  ScopedThreads(const ScopedThreads&) = delete;
  ScopedThreads& operator=(const ScopedThreads&) = delete;

 private:
  int saved_;
};

struct ParticleChunks {
  // ceil(n / kMinSize) chunks, at most kMax: problems of up to kMinSize particles are one
  // chunk, summed exactly as a serial loop would.
  static constexpr Index kMinSize = 512;
  static constexpr int kMax = 64;  // the most threads that can share a scatter

  static int count(Index n) {
    return static_cast<int>(std::clamp<Index>((n + kMinSize - 1) / kMinSize, 1, kMax));
  }
  static Index begin(Index n, int c, int chunks) { return n * c / chunks; }
};

// Below this many iterations a loop stays on one thread (the fork costs more than it saves).
inline constexpr Index kParallelMin = 2048;

// f(i) for i in [0, n), iterations independent of one another.
template <class F>
void parallel_for(Index n, F&& f) {
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
  for (Index i = 0; i < n; ++i) f(i);
}

// f(i) for i in [0, n), then g(j) for j in [0, m), in one parallel region: the two loops must be
// independent (a thread goes on to its share of the second loop when done with its share of the
// first, with no barrier between). A region's fork and join cost 15-130 us on a 2-core virtual
// machine with sleeping threads (OMP_WAIT_POLICY=passive: the longer the threads slept since the
// last region, the more), 2-14 us with spinning ones (a TLS step had 36 regions).
template <class F, class G>
void parallel_for_both(Index n, F&& f, Index m, G&& g) {
#pragma omp parallel if (n + m >= kParallelMin)
  {
#pragma omp for schedule(static) nowait
    for (Index i = 0; i < n; ++i) f(i);
#pragma omp for schedule(static) nowait
    for (Index j = 0; j < m; ++j) g(j);
  }
}

// f(i) for i in [0, n); true when any call returned true (failure flags).
template <class F>
bool parallel_any(Index n, F&& f) {
  bool any = false;
#pragma omp parallel for schedule(static) reduction(|| : any) if (n >= kParallelMin)
  for (Index i = 0; i < n; ++i) any = f(i) || any;
  return any;
}

// f(begin, end) over [0, n) cut into blocks of `block` consecutive indices, blocks in parallel;
// true when any call returned true (failure flags).
template <class F>
bool parallel_any_block(Index n, Index block, F&& f) {
  bool any = false;
  const Index blocks = (n + block - 1) / block;
#pragma omp parallel for schedule(static) reduction(|| : any) if (n >= kParallelMin)
  for (Index k = 0; k < blocks; ++k) any = f(k * block, std::min(n, (k + 1) * block)) || any;
  return any;
}

// f(c, begin, end) for every chunk c of ParticleChunks over n particles, chunks in parallel.
template <class F>
void for_each_chunk(Index n, F&& f) {
  const int k = ParticleChunks::count(n);
#pragma omp parallel for schedule(static) if (k > 1)
  for (int c = 0; c < k; ++c)
    f(c, ParticleChunks::begin(n, c, k), ParticleChunks::begin(n, c + 1, k));
}

// sum_i f(i) over [0, n) with the same rounding for any thread count: partial sums per chunk
// in index order, combined in chunk order. T: double or an Eigen fixed-size vector.
template <class T, class F>
T deterministic_sum(Index n, const T& zero, F&& f) {
  std::array<T, ParticleChunks::kMax> part;
  const int k = ParticleChunks::count(n);
  for_each_chunk(n, [&](int c, Index b, Index e) {
    T acc = zero;
    for (Index i = b; i < e; ++i) acc += f(i);
    part[static_cast<std::size_t>(c)] = acc;
  });
  T total = zero;
  for (int c = 0; c < k; ++c) total += part[static_cast<std::size_t>(c)];
  return total;
}

// The grid DOFs [lo, hi] touched by the stencils of each particle chunk. evaluate_basis, the
// only writer of the stencils, records them while the stencils are in cache.
struct ChunkDofRanges {
  Index particles = -1;  // the particle count they were recorded for; -1: none yet
  std::array<Index, ParticleChunks::kMax> lo{}, hi{};
  // The scatters write only the DOFs between the lowest and highest of the ranges; the others
  // keep what they held. Set by a distributed run, whose grid stages read only the
  // DOFs its particles touch (RunState::dof_window): the grid work of a process then scales
  // with its slab, not with the whole grid. Otherwise every DOF outside the ranges is set to zero.
  bool bounded = false;

  // [lowest, highest] DOF of the ranges (lowest > highest: none recorded).
  std::array<Index, 2> span() const {
    Index first = std::numeric_limits<Index>::max(), last = -1;
    for (int c = 0; c < ParticleChunks::count(particles); ++c) {
      const auto cc = static_cast<std::size_t>(c);
      if (hi[cc] < lo[cc]) continue;
      first = std::min(first, lo[cc]);
      last = std::max(last, hi[cc]);
    }
    return {first, last};
  }

  // [first, end) of the DOFs the scatters write into an output whose window (core/dof_array.hpp)
  // is [first, end): all of them unless `bounded`.
  std::array<Index, 2> written(Index first, Index end) const {
    if (!bounded) return {first, end};
    const auto [lo, hi] = span();
    return lo <= hi ? std::array<Index, 2>{lo, hi + 1} : std::array<Index, 2>{first, first};
  }
  // Whether every chunk's DOFs lie in the window [first, end) (a distributed run's grid arrays
  // hold only the DOFs of its slab: RunState::fit_dof_window).
  bool within(Index first, Index end) const {
    for (int c = 0; c < ParticleChunks::count(particles); ++c) {
      const auto cc = static_cast<std::size_t>(c);
      if (lo[cc] <= hi[cc] && (lo[cc] < first || hi[cc] >= end)) return false;
    }
    return true;
  }

  // Scans the stencils (fallback when evaluate_basis did not record them).
  // stride: the DOF strides of a tensor-product basis (for its compact stencils). dof_bounds
  // is the stencil's own (basis/stencil.hpp), found by argument-dependent lookup: the ground
  // layer does not include the numerics.
  template <class Stencil, class Stride>
  void scan(const std::vector<Stencil>& stencils, const Stride& stride) {
    const auto n = static_cast<Index>(stencils.size());
    for_each_chunk(n, [&](int c, Index b, Index e) { record(c, stencils, stride, b, e); });
    particles = n;
  }
  template <class Stencil, class Stride>
  void record(int c, const std::vector<Stencil>& stencils, const Stride& stride, Index b, Index e) {
    Index l = std::numeric_limits<Index>::max(), h = -1;
    for (Index p = b; p < e; ++p) {
      const auto [sl, sh] = dof_bounds(stencils[static_cast<std::size_t>(p)], stride);
      l = std::min(l, sl);
      h = std::max(h, sh);
    }
    lo[static_cast<std::size_t>(c)] = l;
    hi[static_cast<std::size_t>(c)] = h;
  }
};

// Per-chunk grid buffers of one value type (double or Vec<Dim>) for the particle-to-grid sums.
template <class T>
class GridAccumulator {
 public:
  // One chunk's view: add into the DOFs of its range.
  struct Slice {
    T* data;
    Index lo;
    int chunk;  // the particle chunk it belongs to (for per-chunk particle sums)
    T& operator[](Index dof) const { return data[dof - lo]; }
  };

  // out_i = sum_p contributions, where scatter(p, slice) adds particle p's contributions into
  // slice[dof]. Every chunk sums its particles in order into its own slice; the slices are
  // then added into `out` in chunk order. DOFs of out's window outside every range are set to
  // zero (or, with ChunkDofRanges::bounded, keep their values).
  template <class F>
  void scatter(DofArray<T>& out, const T& zero, const ChunkDofRanges& r, F&& scatter);

  // Lays out one slice per chunk of r (grows the buffer only: no allocation once steady).
  void reserve(const ChunkDofRanges& r) {
    const int k = ParticleChunks::count(r.particles);
    std::size_t size = 0;
    for (int c = 0; c < k; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      offset_[cc] = size;
      size += static_cast<std::size_t>(std::max<Index>(0, r.hi[cc] - r.lo[cc] + 1));
    }
    if (buf_.size() < size) buf_.resize(size);
  }
  // Chunk c's slice, zeroed (c has a non-empty range).
  Slice zero_slice(int c, const ChunkDofRanges& r, const T& zero) {
    const auto cc = static_cast<std::size_t>(c);
    T* data = buf_.data() + offset_[cc];
    std::fill(data, data + (r.hi[cc] - r.lo[cc] + 1), zero);
    return {data, r.lo[cc], c};
  }
  // out[b, e) = the sum of the slices over those DOFs, in chunk order.
  void reduce(DofArray<T>& out, const T& zero, const ChunkDofRanges& r, Index b, Index e) const {
    // Plain pointers into the window and the slices: the fill and the additions run as over
    // vectors (a loop through DofArray's indexing instead of the fill was measured slower on a
    // grid-dominated problem).
    std::fill(out.data() + (b - out.first()), out.data() + (e - out.first()), zero);
    const int k = ParticleChunks::count(r.particles);
    for (int c = 0; c < k; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      const Index lo = std::max(b, r.lo[cc]), hi = std::min(e, r.hi[cc] + 1);
      if (lo >= hi) continue;
      T* o = out.data() + (lo - out.first());
      const T* data = buf_.data() + offset_[cc] + (lo - r.lo[cc]);
      for (Index j = 0; j < hi - lo; ++j) o[j] += data[j];
    }
  }

 private:
  std::vector<T> buf_;  // the slices of all chunks, back to back
  std::array<std::size_t, ParticleChunks::kMax> offset_{};
};

// One output of scatter_fused: the grid array and the accumulator whose slices sum into it.
template <class T>
struct ScatterTarget {
  GridAccumulator<T>& acc;
  DofArray<T>& out;
  T zero;
};

// Several particle-to-grid sums in one pass over the particles: scatter(p, slices...) adds
// particle p's contributions into one slice per target (in the order of the targets). Each
// output gets the same bits as a scatter of its own (same chunks, same order per chunk and
// per DOF). The outputs have the same number of DOFs.
template <class F, class... T>
void scatter_fused(const ChunkDofRanges& r, F&& scatter, ScatterTarget<T>... t) {
  const Index n = r.particles;
  const int k = ParticleChunks::count(n);
  (t.acc.reserve(r), ...);
  const auto& out0 = std::get<0>(std::tie(t.out...));
  // The outputs share one window; a sum reaching past it would lose what falls outside.
  if (((t.out.first() != out0.first() || t.out.stop() != out0.stop()) || ...) ||
      !r.within(out0.first(), out0.stop()))
    throw std::logic_error("a particle-to-grid sum reaches DOFs outside its grid arrays' window");
  const auto written = r.written(out0.first(), out0.stop());
  const Index first = written[0], end = written[1];
  constexpr Index kBlock = 4096;  // DOFs per reduction task
  const Index blocks = (end - first + kBlock - 1) / kBlock;
#pragma omp parallel if (n >= kParallelMin)
  {
#pragma omp for schedule(static)
    for (int c = 0; c < k; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      if (r.hi[cc] < r.lo[cc]) continue;
      const auto slices = std::make_tuple(t.acc.zero_slice(c, r, t.zero)...);
      const Index e = ParticleChunks::begin(n, c + 1, k);
      for (Index p = ParticleChunks::begin(n, c, k); p < e; ++p)
        std::apply([&](const auto&... s) { scatter(p, s...); }, slices);
    }
    // The implicit barrier above: every slice is complete before any is added.
#pragma omp for schedule(static)
    for (Index blk = 0; blk < blocks; ++blk) {
      const Index b = first + blk * kBlock, e = std::min(end, b + kBlock);
      (t.acc.reduce(t.out, t.zero, r, b, e), ...);
    }
  }
}

template <class T>
template <class F>
void GridAccumulator<T>::scatter(DofArray<T>& out, const T& zero, const ChunkDofRanges& r, F&& f) {
  scatter_fused(r, f, ScatterTarget<T>{*this, out, zero});
}

// Per-chunk partial sums of a particle quantity taken inside a scatter (the chunk's particles in
// order), combined in chunk order: the bits of deterministic_sum over the same particles, without
// a pass of its own. One cache line per chunk, so threads do not share lines.
template <class T>
class ChunkSums {
 public:
  void reset(const T& zero) {
    for (auto& p : part_) p.value = zero;
  }
  T& operator[](int chunk) { return part_[static_cast<std::size_t>(chunk)].value; }
  T total(Index n, const T& zero) const {
    T t = zero;
    for (int c = 0; c < ParticleChunks::count(n); ++c)
      t += part_[static_cast<std::size_t>(c)].value;
    return t;
  }

 private:
  struct alignas(64) Part {
    T value;
  };
  std::array<Part, ParticleChunks::kMax> part_;
};

// The scatter state a simulation keeps between steps: chunk ranges and buffers.
template <int Dim>
struct ScatterBuffers {
  ChunkDofRanges ranges;
  GridAccumulator<double> scalar;
  GridAccumulator<Vec<Dim>> vector;
  GridAccumulator<Vec<Dim>> vector2;  // the second vector sum of a fused scatter
  // The particle sums of the conservation checks (stages::after_mass, after_momentum),
  // taken by a mapping's scatter when it reads the same particle data: sum m_p, and
  // (sum m_p v_p, sum m_p |v_p|). `has_*`: set by the scatter, cleared by the check that uses it.
  using MomentumSums = Eigen::Matrix<double, Dim + 1, 1>;
  ChunkSums<double> particle_mass;
  ChunkSums<MomentumSums> particle_momentum;
  bool has_particle_mass = false;
  bool has_particle_momentum = false;
};

}  // namespace mpm
