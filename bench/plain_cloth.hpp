// Plain implementations the benchmark compares the testbed with: a cloth
// right-hand side and a Baraff–Witkin step written directly over arrays, with no framework
// between them and the arithmetic. Both read their geometry (points, masses, pins, springs,
// gravity) from the same MassSpringNetwork the testbed integrates, and use the testbed's state
// layout y = [x; v] with coordinates interleaved per point, so results compare entry by entry.
// Only undamped 3D networks (the cloth defaults): a network with point damping or dashpots is
// refused (std::invalid_argument).
#pragma once

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "models/mass_spring/network.hpp"

namespace stiffbench::bench {

// a_i = (1/m_i) Σ_springs k (l − L) (x_j − x_i)/l + g for free points, 0 for pinned ones
// (network.hpp's forces without damping). Per-point gather over CSR adjacency lists with
// 24-byte entries (k, L, 32-bit neighbour index), OpenMP over points (static schedule): every
// spring is evaluated from both ends.
class PlainClothRhs {
 public:
  explicit PlainClothRhs(const MassSpringNetwork& net);
  void acceleration(const double* x, double* a) const;
  Index points() const { return static_cast<Index>(inv_mass_.size()); }
  Index springs() const { return springs_; }

 private:
  struct Entry {
    double k, rest;
    std::int32_t other;
  };
  std::vector<std::int32_t> start_;
  std::vector<Entry> adj_;
  std::vector<double> inv_mass_;  // 0 for pinned points
  double g_[3] = {0, 0, 0};
  Index springs_ = 0;
};

// One Baraff–Witkin step (Baraff & Witkin 1998, velocity form, no damping):
//   (M − h² K_f) Δv = h (f + h K_f v),  v⁺ = v + Δv,  x⁺ = x + h v⁺,
// over the free points only (pinned points' Δv = 0 is eliminated, so the matrix is symmetric and,
// for a network whose −K_f is positive semi-definite, SPD). K_f's 3×3 block for a spring (i, j)
// is J = k [d dᵀ + (1 − L/l)(I − d dᵀ)] (network.hpp): the matrix's block (i, j) is −h² J and
// its diagonal block m_i I + h² Σ_j J. The matrix is row-major with a pattern fixed at
// construction; every step writes its values in place (OpenMP over free points, each point
// gathering its own springs) together with the right-hand side, then solves with Eigen's
// ConjugateGradient (Lower|Upper: Eigen's multi-threaded sparse product) and a Jacobi
// preconditioner at relative residual `tol`, warm-started from the previous step's Δv.
class PlainBaraffWitkin {
 public:
  PlainBaraffWitkin(const MassSpringNetwork& net, double tol);
  // Advances y = [x; v] (testbed layout, all points) by h.
  void step(double* y, double h);
  // Forgets the warm start (the next step's CG starts from Δv = 0).
  void reset() { dv_.setZero(); }
  double last_assembly_s() const { return assembly_s_; }
  double last_solve_s() const { return solve_s_; }
  long last_iterations() const { return iterations_; }
  Index free_points() const { return static_cast<Index>(free_.size()); }

 private:
  struct Nb {
    std::int32_t other;       // point index
    std::int32_t block = -1;  // slot of block (i, other) within the row, -1 when other is pinned
    double k, rest;
  };
  Index np_ = 0;
  std::vector<std::int32_t> free_;      // free point indices
  std::vector<std::int32_t> free_of_;   // point -> free index, -1 pinned
  std::vector<std::int32_t> nb_start_;  // per free point (CSR over nb_)
  std::vector<Nb> nb_;
  std::vector<std::int32_t> diag_slot_;   // per free point: slot of its diagonal block in its row
  std::vector<std::int32_t> row_blocks_;  // per free point: number of blocks in its rows
  std::vector<double> mass_;              // per free point
  double g_[3] = {0, 0, 0};
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> a_;
  Eigen::VectorXd b_, dv_, guess_;
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double, Eigen::RowMajor, int>,
                           Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>>
      cg_;
  double assembly_s_ = 0.0, solve_s_ = 0.0;
  long iterations_ = 0;
};

}  // namespace stiffbench::bench
