// Basic vocabulary shared by every layer: vector views and the error types that map to the
// command line's exit codes (2 for bad input, 1 for anything else).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <stdexcept>
#include <string>

namespace stiffbench {

using Index = Eigen::Index;
using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;
using SparseMat = Eigen::SparseMatrix<double>;
// Contiguous views: a SUNDIALS N_Vector's data or a GSL array can be mapped onto these without
// a copy (Eigen::Map converts to Ref with inner stride 1).
using VecRef = Eigen::Ref<Vec>;
using CVecRef = Eigen::Ref<const Vec>;

// Input the user got wrong: an unknown name, a malformed or out-of-range value, an incompatible
// model/integrator pair. The message names the bad value. Maps to exit code 2.
class BadInput : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws BadInput(message) unless cond holds.
inline void require_input(bool cond, const std::string& message) {
  if (!cond) throw BadInput(message);
}

}  // namespace stiffbench
