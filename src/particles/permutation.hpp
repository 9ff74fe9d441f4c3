#pragma once
// A permutation of the particles (re-sorting by cell, state/sort.hpp; output in id order) and its
// application to each per-particle array of the field list.
#include <algorithm>
#include <cstddef>
#include <new>
#include <type_traits>
#include <vector>

#include "core/parallel.hpp"
#include "core/types.hpp"
#include "particles/material_state.hpp"

namespace mpm {

// One permutation of the particles: after apply(v), v[k] is the old v[order[k]].
class Permutation {
 public:
  // 32-bit like the ids (core/types.hpp: a run holds fewer than 2^31 particles).
  std::vector<CompactIndex> order;    // new index -> old index
  std::vector<CompactIndex> inverse;  // old index -> new index (set_inverse)

  Index size() const { return static_cast<Index>(order.size()); }
  void set_inverse() {
    inverse.resize(order.size());
    parallel_for(size(), [&](Index k) {
      inverse[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] =
          static_cast<CompactIndex>(k);
    });
  }
  bool identity() const {
    for (std::size_t k = 0; k < order.size(); ++k)
      if (order[k] != static_cast<Index>(k)) return false;
    return true;
  }

  // Reorders one particle-indexed array: a parallel gather into a scratch buffer shared by all
  // arrays (grown only, so no allocation once steady), then a streaming copy back.
  template <class T>
  void apply(std::vector<T>& v) {
    static_assert(std::is_trivially_destructible_v<T> && alignof(T) <= alignof(Word));
    const Index n = size();
    const std::size_t words =
        (static_cast<std::size_t>(n) * sizeof(T) + sizeof(Word) - 1) / sizeof(Word);
    if (scratch_.size() < words) scratch_.resize(words);
    T* tmp = reinterpret_cast<T*>(scratch_.data());
    parallel_for(n, [&](Index k) {
      ::new (static_cast<void*>(tmp + k))
          T(v[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])]);
    });
    const T* src = std::launder(tmp);
    parallel_for(n, [&](Index k) { v[static_cast<std::size_t>(k)] = src[k]; });
  }
  // The rows of a material's internal variables (through a scratch array of their own).
  void apply(MaterialState& s) { s.permute(order, state_scratch_); }

 private:
  // Aligned for any particle field: with AVX (MPM_NATIVE), Eigen's fixed 2 x 2 and 4-vectors
  // are 32-byte aligned, more than std::max_align_t.
  struct alignas(64) Word {
    unsigned char bytes[64];
  };
  std::vector<Word> scratch_;  // n values of the largest array type
  std::vector<double> state_scratch_;
};

}  // namespace mpm
