// Frame output of `solve --frames N --out DIR`: for a model with particles, one VTK XML
// UnstructuredGrid file per frame (DIR/frame_0000.vtu, ...; points with vertex cells, point data
// from the model's ParticleFrame) and a ParaView time collection DIR/frames.pvd; for every model,
// DIR/observables.csv (t, then the model's invariants and observables, one row per frame).
// Files are rewritten atomically after every frame, so an interrupted run leaves a complete
// collection and table of the frames written so far.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/ode_system.hpp"

namespace stiffbench {

// The VTK XML text of one frame (ASCII, Float64 points).
std::string vtu_text(const ParticleFrame& frame);

class FrameWriter {
 public:
  // Creates DIR (BadInput when it cannot be created or is not a directory).
  FrameWriter(const OdeSystem& sys, std::filesystem::path dir);

  // Records the state at t: a VTK frame (particle models) and a row of observables.csv.
  void write(double t, CVecRef y);

  long frames() const { return frames_; }
  const std::filesystem::path& dir() const { return dir_; }
  // Column names of observables.csv after t.
  const std::vector<std::string>& columns() const { return columns_; }

 private:
  const OdeSystem& sys_;
  std::filesystem::path dir_;
  std::vector<Invariant> quantities_;
  std::vector<std::string> columns_;
  std::string csv_, pvd_entries_;
  long frames_ = 0;
};

}  // namespace stiffbench
