// The order in which tbb::parallel_deterministic_reduce adds its leaves, written down so that the
// same sums can be formed from leaves computed anywhere (work units of measure/replicates.hpp, a
// share of them by another process: measure/shards.hpp). Over tbb::blocked_range(0, n, grain)
// the reduce splits a range [b, e) while e - b > grain, at b + (e - b) / 2; each leaf starts
// from the identity and a node's value is its left child's plus its right child's
// (left += right). The leaves are blocks of at most `grain` consecutive items, in order.
#pragma once
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

#include "microsim/measure/shards.hpp"

namespace microsim {

class HalvingTree {
 public:
  HalvingTree(std::uint64_t n, std::uint64_t grain) {
    if (n > 0) split(0, n, grain < 1 ? 1 : grain);
  }
  // The leaves, in order: blocks of consecutive items [first, end).
  const std::vector<UnitRange>& leaves() const { return leaves_; }
  // How many joins the post-order walk of the tree makes right after leaf l arrives: the
  // subtrees that leaf l completes.
  int joins_after(std::size_t l) const { return joins_after_[l]; }
  std::uint64_t largest_leaf() const {
    std::uint64_t m = 0;
    for (const UnitRange& r : leaves_) m = r.size() > m ? r.size() : m;
    return m;
  }

 private:
  void split(std::uint64_t b, std::uint64_t e, std::uint64_t grain) {
    if (e - b <= grain) {
      leaves_.push_back({b, e});
      joins_after_.push_back(0);
      return;
    }
    const std::uint64_t m = b + (e - b) / 2;
    split(b, m, grain);
    split(m, e, grain);
    ++joins_after_.back();  // [b, m) + [m, e): after the last leaf of [m, e)
  }
  std::vector<UnitRange> leaves_;
  std::vector<int> joins_after_;
};

// The tree's sum of leaf values handed over in leaf order: a stack of finished subtrees, at most
// the tree's depth + 1 values held at a time.
template <class T>
class HalvingSum {
 public:
  explicit HalvingSum(const HalvingTree& tree) : tree_(tree) {}
  void add(T&& leaf) {
    if (next_ >= tree_.leaves().size()) throw std::logic_error("HalvingSum: more leaves than the tree's");
    stack_.push_back(std::move(leaf));
    for (int j = tree_.joins_after(next_); j > 0; --j) {
      T right = std::move(stack_.back());
      stack_.pop_back();
      stack_.back() += right;
    }
    ++next_;
  }
  // The sum, once every leaf is in.
  T result() {
    if (next_ != tree_.leaves().size() || stack_.size() != 1)
      throw std::logic_error("HalvingSum: the sum is taken before its last leaf");
    return std::move(stack_.back());
  }

 private:
  const HalvingTree& tree_;
  std::vector<T> stack_;
  std::size_t next_ = 0;
};

}  // namespace microsim
