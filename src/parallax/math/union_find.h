#pragma once

#include <cstddef>
#include <numeric>
#include <vector>

namespace parallax {

// Disjoint sets over [0, n) with path halving and union by size.
class UnionFind {
 public:
  explicit UnionFind(size_t num_elements) : parent_(num_elements), size_(num_elements, 1) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }

  size_t Find(size_t element) {
    while (parent_[element] != element) {
      parent_[element] = parent_[parent_[element]];
      element = parent_[element];
    }
    return element;
  }

  // Returns false when both were already in one set.
  bool Union(size_t a, size_t b) {
    a = Find(a);
    b = Find(b);
    if (a == b) return false;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
    return true;
  }

  size_t SetSize(size_t element) { return size_[Find(element)]; }
  size_t NumElements() const { return parent_.size(); }

 private:
  std::vector<size_t> parent_;
  std::vector<size_t> size_;
};

}  // namespace parallax
