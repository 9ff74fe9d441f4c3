#pragma once
// A grid array over a window of the DOFs: indexed by the global DOF number, it holds
// the DOFs [first(), stop()) only. On one process the window is every DOF of the basis; a
// distributed run keeps the DOFs its slab's particles touch (RunState::fit_dof_window), so that a
// process's grid memory grows with its slab, not with the whole grid. Iteration (begin, end,
// size, data) covers the window.
#include <algorithm>
#include <cassert>
#include <concepts>
#include <cstddef>
#include <vector>

#include "core/types.hpp"

namespace mpm {

template <class T>
class DofArray {
 public:
  using value_type = T;

  // The window [first, first + count), every value `fill`.
  void assign(Index first, Index count, const T& fill) {
    first_ = first;
    v_.assign(static_cast<std::size_t>(count), fill);
  }
  // Moves the window to [first, first + count): the DOFs in both windows keep their values, the
  // new ones get `fill`. (A window moved between two sums of a step keeps the first sum.)
  void rewindow(Index first, Index count, const T& fill) {
    std::vector<T> next(static_cast<std::size_t>(count), fill);
    const Index lo = std::max(first, first_), hi = std::min(first + count, stop());
    for (Index i = lo; i < hi; ++i)
      next[static_cast<std::size_t>(i - first)] = v_[static_cast<std::size_t>(i - first_)];
    v_ = std::move(next);
    first_ = first;
  }

  // DOF i (global number), which the window must hold (checked in builds with assertions).
  template <std::integral I>
  T& operator[](I i) {
    assert(holds(static_cast<Index>(i)));
    return v_[static_cast<std::size_t>(static_cast<Index>(i) - first_)];
  }
  template <std::integral I>
  const T& operator[](I i) const {
    assert(holds(static_cast<Index>(i)));
    return v_[static_cast<std::size_t>(static_cast<Index>(i) - first_)];
  }

  // The window's values and first DOF number as two locals, for a per-particle loop that calls
  // functions the compiler cannot see into (a material law), after which it would reload both
  // from the array: view[i] is (*this)[i] (measured on a grid-dominated problem).
  template <class U>
  struct View {
    U* data;
    Index first;
    template <std::integral I>
    U& operator[](I i) const {
      return data[static_cast<Index>(i) - first];
    }
  };
  View<T> view() { return {v_.data(), first_}; }
  View<const T> view() const { return {v_.data(), first_}; }

  Index first() const { return first_; }
  Index stop() const { return first_ + static_cast<Index>(v_.size()); }
  bool holds(Index i) const { return i >= first_ && i < stop(); }
  // The window's DOF count, its values in DOF order from first().
  std::size_t size() const { return v_.size(); }
  bool empty() const { return v_.empty(); }
  auto begin() { return v_.begin(); }
  auto end() { return v_.end(); }
  auto begin() const { return v_.begin(); }
  auto end() const { return v_.end(); }
  T* data() { return v_.data(); }
  const T* data() const { return v_.data(); }

 private:
  Index first_ = 0;
  std::vector<T> v_;
};

}  // namespace mpm
