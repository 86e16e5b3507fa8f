#include "integrators/solvers/sparse_assembly.hpp"

#include <algorithm>

namespace stiffbench {

void SparseCombination::build(const std::vector<SparseTerm>& terms) {
  const Index n = terms.front().matrix->rows();
  std::vector<Eigen::Triplet<double>> trips;
  for (const auto& t : terms)
    for (Index c = 0; c < t.matrix->outerSize(); ++c)
      for (SparseMat::InnerIterator it(*t.matrix, c); it; ++it)
        trips.emplace_back(it.row(), it.col(), 1.0);
  w_.resize(n, terms.front().matrix->cols());
  w_.setFromTriplets(trips.begin(), trips.end());  // duplicates summed: structure is the union
  w_.makeCompressed();
  maps_.assign(terms.size(), {});
  outer_.assign(terms.size(), {});
  inner_.assign(terms.size(), {});
  for (std::size_t k = 0; k < terms.size(); ++k) {
    const SparseMat& a = *terms[k].matrix;
    outer_[k].assign(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1);
    inner_[k].assign(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
    auto& map = maps_[k];
    map.reserve(static_cast<std::size_t>(a.nonZeros()));
    for (Index c = 0; c < a.outerSize(); ++c) {
      const int* begin = w_.innerIndexPtr() + w_.outerIndexPtr()[c];
      const int* end = w_.innerIndexPtr() + w_.outerIndexPtr()[c + 1];
      for (SparseMat::InnerIterator it(a, c); it; ++it) {
        const int* pos = std::lower_bound(begin, end, static_cast<int>(it.row()));
        map.push_back(pos - w_.innerIndexPtr());
      }
    }
  }
}

bool SparseCombination::same_patterns(const std::vector<SparseTerm>& terms) const {
  if (terms.size() != maps_.size()) return false;
  for (std::size_t k = 0; k < terms.size(); ++k) {
    const SparseMat& a = *terms[k].matrix;
    if (!a.isCompressed() || static_cast<std::size_t>(a.nonZeros()) != inner_[k].size() ||
        static_cast<std::size_t>(a.outerSize() + 1) != outer_[k].size())
      return false;
    if (!std::equal(outer_[k].begin(), outer_[k].end(), a.outerIndexPtr())) return false;
    if (!std::equal(inner_[k].begin(), inner_[k].end(), a.innerIndexPtr())) return false;
  }
  return true;
}

void SparseCombination::assemble(const std::vector<SparseTerm>& terms) {
  double* w = w_.valuePtr();
  std::fill(w, w + w_.nonZeros(), 0.0);
  for (std::size_t k = 0; k < terms.size(); ++k) {
    const SparseMat& a = *terms[k].matrix;
    const double c = terms[k].coeff;
    const double* v = a.valuePtr();
    const int* rows = a.innerIndexPtr();
    const auto& map = maps_[k];
    if (terms[k].row_scale) {
      const Vec& s = *terms[k].row_scale;
      for (std::size_t i = 0; i < map.size(); ++i) w[map[i]] += c * s[rows[i]] * v[i];
    } else {
      for (std::size_t i = 0; i < map.size(); ++i) w[map[i]] += c * v[i];
    }
  }
}

}  // namespace stiffbench
