// W = Σ_k c_k · diag(s_k) · A_k assembled into one fixed pattern (the union of the inputs'
// patterns) without allocation: the index of every input nonzero in W's value array is
// computed once by build(). Used for Newton matrices I - hγJ and the Baraff–Witkin matrix
// M - hMD - h²MK, whose patterns do not change during a run, so the linear solver's symbolic
// analysis is done once.
#pragma once

#include <vector>

#include "core/types.hpp"

namespace stiffbench {

struct SparseTerm {
  double coeff = 1.0;
  const SparseMat* matrix = nullptr;  // compressed, column-major
  const Vec* row_scale = nullptr;     // optional diag(s) applied from the left
};

class SparseCombination {
 public:
  // Computes the union pattern and index maps. Returns true (pattern (re)built).
  void build(const std::vector<SparseTerm>& terms);
  // Whether every term still has the pattern seen by build().
  bool same_patterns(const std::vector<SparseTerm>& terms) const;
  // Fills the values of W; the terms must have the patterns seen by build().
  void assemble(const std::vector<SparseTerm>& terms);
  const SparseMat& matrix() const { return w_; }
  SparseMat& matrix() { return w_; }

 private:
  SparseMat w_;
  std::vector<std::vector<Index>> maps_;         // per term: position in w_ of each nonzero
  std::vector<std::vector<int>> outer_, inner_;  // per term: the pattern seen by build()
};

}  // namespace stiffbench
