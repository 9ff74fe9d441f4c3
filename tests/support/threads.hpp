#pragma once
// Helpers of the tests that compare runs on different thread counts (tests/scheme/test_parallel,
// tests/scheme/test_sort, tests/mapping/test_mapping_parallel).
#include <cstring>
#include <vector>

#include "core/parallel.hpp"

namespace mpm::test {

// Sets the OpenMP thread count for a scope and restores the previous count when it ends.
using Threads = ScopedThreads;

// Byte-for-byte equality of two arrays (the thread-count tests demand the same bits, not
// closeness; NaNs with equal payloads compare equal, as they should here). Empty arrays may
// hold a null data(), which memcmp must not be given even for zero bytes.
template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}
// The same for grid arrays (core/dof_array.hpp), which must hold the same window.
template <class T>
bool same_bits(const DofArray<T>& a, const DofArray<T>& b) {
  return a.first() == b.first() && a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

}  // namespace mpm::test
