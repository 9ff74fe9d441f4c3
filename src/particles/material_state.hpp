#pragma once
// The internal variables of a material at the particles: a row of `width` doubles per particle
// (the law's kStateNames, material/materials.hpp), stored in one contiguous array. Particles
// holds it in its one field list, so whatever sorts, copies, migrates, checkpoints or writes the
// particles carries it. An elastic law declares none: width 0, no storage and no output column.
#include <algorithm>
#include <cstddef>
#include <cstring>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace mpm {

class MaterialState {
 public:
  // The names of the variables, one per column (the laws' static kStateNames).
  std::span<const std::string_view> names() const { return names_; }
  std::size_t width() const { return names_.size(); }
  std::size_t size() const { return n_; }

  // Gives the rows the columns `names`. Rows that already hold that many values keep them (a
  // restart's, read by set_raw); other rows of fresh particles get every value 0 (a law's state
  // starts at zero); raw rows of another width are std::invalid_argument.
  void set_names(std::span<const std::string_view> names) {
    if (values_.size() != n_ * names.size()) {
      if (raw_)
        throw std::invalid_argument(
            "the particles carry " + std::to_string(n_ == 0 ? 0 : values_.size() / n_) +
            " internal variables each, the material declares " + std::to_string(names.size()));
      values_.assign(n_ * names.size(), 0.0);
    }
    std::vector<std::string_view> fresh(names.begin(), names.end());  // names may be names_
    names_.swap(fresh);
    raw_ = false;
  }
  // n rows of unnamed values, row after row (a checkpoint's, before set_names names them).
  void set_raw(std::size_t n, std::vector<double> values) {
    n_ = n;
    values_ = std::move(values);
    raw_ = true;
  }

  std::span<double> operator[](std::size_t i) { return {values_.data() + i * width(), width()}; }
  std::span<const double> operator[](std::size_t i) const {
    return {values_.data() + i * width(), width()};
  }
  // Every value, row after row.
  const std::vector<double>& values() const { return values_; }

  // The vector-of-rows operations of the field list (particles/particles.hpp).
  void resize(std::size_t n) {
    values_.resize(n * width(), 0.0);
    n_ = n;
  }
  void reserve(std::size_t n) { values_.reserve(n * width()); }
  std::size_t capacity() const { return width() == 0 ? n_ : values_.capacity() / width(); }
  void shrink_capacity_to(std::size_t n) {
    std::vector<double> fresh;
    fresh.reserve(n * width());
    fresh.assign(values_.begin(), values_.end());
    values_.swap(fresh);
  }
  void copy_row(std::size_t to, std::size_t from) {
    std::copy_n(values_.begin() + static_cast<std::ptrdiff_t>(from * width()), width(),
                values_.begin() + static_cast<std::ptrdiff_t>(to * width()));
  }
  std::size_t row_bytes() const { return width() * sizeof(double); }
  const std::byte* row_data(std::size_t i) const {
    return reinterpret_cast<const std::byte*>(values_.data() + i * width());
  }
  void append_row(const std::byte* bytes) {
    values_.resize(values_.size() + width());
    if (width() > 0) std::memcpy(values_.data() + n_ * width(), bytes, row_bytes());
    ++n_;
  }
  // Row k becomes the old row order[k] (sorting: state/sort.hpp), through `scratch`.
  template <class Order>
  void permute(const Order& order, std::vector<double>& scratch) {
    if (width() == 0) return;
    scratch.resize(values_.size());
    for (std::size_t k = 0; k < order.size(); ++k)
      std::copy_n(values_.begin() + static_cast<std::ptrdiff_t>(order[k] * width()), width(),
                  scratch.begin() + static_cast<std::ptrdiff_t>(k * width()));
    values_.swap(scratch);
  }

 private:
  std::vector<std::string_view> names_;
  std::vector<double> values_;
  std::size_t n_ = 0;
  bool raw_ = false;
};

}  // namespace mpm
