// Frame output of `solve --frames N --out DIR`: for a model with particles, one VTK file per
// frame — XML UnstructuredGrid DIR/frame_0000.vtu, ... (points with vertex cells, point data from
// the model's ParticleFrame) with a ParaView time collection DIR/frames.pvd, or legacy
// DIR/frame_0000.vtk, ... (POLYDATA with vertices) — and the same frame as CSV for gnuplot
// (DIR/frame_0000.csv: x,y,z, then one column per scalar field and vector component, e.g.
// density,pressure,velocity_x,velocity_y,velocity_z,fluid); for every model, DIR/observables.csv
// (t, then the model's invariants and observables, one row per frame). A grid model (has_grid)
// writes VTK image data instead — XML DIR/frame_0000.vti (ImageData, one cell per grid cell,
// CellData from its GridFrame) in the same frames.pvd collection, or legacy STRUCTURED_POINTS
// DIR/frame_0000.vtk with CELL_DATA — and the frame CSV at the cell centres. Every model's
// profiles() are written as DIR/<name>.csv at every frame (the last frame's values remain).
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
// The VTK XML ImageData text of a grid frame (ASCII Float64 cell data).
std::string vti_text(const GridFrame& frame);
// The legacy VTK STRUCTURED_POINTS text of a grid frame (CELL_DATA).
std::string legacy_vtk_grid_text(const GridFrame& frame, double t);
// The grid frame as points at the cell centres (for the frame CSV).
ParticleFrame cell_centres(const GridFrame& frame);

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
