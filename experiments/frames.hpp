// Frame output of `solve --frames N --out DIR`: for a model with particles, one VTK file per
// frame — XML UnstructuredGrid DIR/frame_0000.vtu, ... (points with vertex cells, point data from
// the model's ParticleFrame) with a ParaView time collection DIR/frames.pvd, or legacy
// DIR/frame_0000.vtk, ... (POLYDATA with vertices) — and the same frame as CSV for gnuplot
// (DIR/frame_0000.csv: x,y,z, then one column per scalar field and vector component, e.g.
// density,pressure,velocity_x,velocity_y,velocity_z,fluid); for every model, DIR/observables.csv
// (t, then the model's invariants and observables, one row per frame).
// Files are rewritten atomically after every frame, so an interrupted run leaves a complete
// collection and table of the frames written so far.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/ode_system.hpp"

namespace stiffbench {

enum class FrameFormat { vtu, vtk };

// The VTK XML text of one frame (ASCII, Float64 points).
std::string vtu_text(const ParticleFrame& frame);
// The legacy VTK text of one frame (ASCII POLYDATA, a vertex per point).
std::string legacy_vtk_text(const ParticleFrame& frame, double t);
// The CSV text of one frame (header x,y,z,<fields>).
std::string frame_csv_text(const ParticleFrame& frame);

class FrameWriter {
 public:
  // Creates DIR (BadInput when it cannot be created or is not a directory).
  FrameWriter(const OdeSystem& sys, std::filesystem::path dir,
              FrameFormat format = FrameFormat::vtu);

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
  FrameFormat format_;
  long frames_ = 0;
};

}  // namespace stiffbench
