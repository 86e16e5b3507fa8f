#include "experiments/output/frames.hpp"

#include <cstdio>
#include <sstream>

#include "core/params.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

std::string vtu_text(const ParticleFrame& frame) {
  const Index n = frame.points();
  std::ostringstream os;
  os << "<?xml version=\"1.0\"?>\n"
     << "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
     << "  <UnstructuredGrid>\n"
     << "    <Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << n << "\">\n"
     << "      <PointData>\n";
  for (const auto& f : frame.fields) {
    os << "        <DataArray type=\"Float64\" Name=\"" << f.name << "\" NumberOfComponents=\""
       << f.components << "\" format=\"ascii\">\n";
    for (std::size_t k = 0; k < f.values.size(); ++k)
      os << (k % static_cast<std::size_t>(f.components) ? " " : "\n") << format_full(f.values[k]);
    os << "\n        </DataArray>\n";
  }
  os << "      </PointData>\n      <Points>\n"
     << "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">";
  for (std::size_t k = 0; k < frame.positions.size(); ++k)
    os << (k % 3 ? " " : "\n") << format_full(frame.positions[k]);
  os << "\n        </DataArray>\n      </Points>\n      <Cells>\n"
     << "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (Index i = 0; i < n; ++i) os << i << (i + 1 < n ? " " : "\n");
  os << "        </DataArray>\n"
     << "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (Index i = 0; i < n; ++i) os << i + 1 << (i + 1 < n ? " " : "\n");
  os << "        </DataArray>\n"
     << "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";  // 1 = VTK_VERTEX
  for (Index i = 0; i < n; ++i) os << 1 << (i + 1 < n ? " " : "\n");
  os << "        </DataArray>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  return os.str();
}

std::string legacy_vtk_text(const ParticleFrame& frame, double t) {
  const Index n = frame.points();
  std::ostringstream os;
  os << "# vtk DataFile Version 3.0\nstiffbench particle frame t = " << format_full(t)
     << "\nASCII\nDATASET POLYDATA\nPOINTS " << n << " double\n";
  for (std::size_t k = 0; k < frame.positions.size(); ++k)
    os << format_full(frame.positions[k]) << (k % 3 == 2 ? "\n" : " ");
  os << "VERTICES " << n << " " << 2 * n << "\n";
  for (Index i = 0; i < n; ++i) os << "1 " << i << "\n";
  os << "POINT_DATA " << n << "\n";
  for (const auto& f : frame.fields) {
    if (f.components == 3)
      os << "VECTORS " << f.name << " double\n";
    else
      os << "SCALARS " << f.name << " double 1\nLOOKUP_TABLE default\n";
    for (std::size_t k = 0; k < f.values.size(); ++k)
      os << format_full(f.values[k])
         << (k % static_cast<std::size_t>(f.components) ==
                     static_cast<std::size_t>(f.components) - 1
                 ? "\n"
                 : " ");
  }
  return os.str();
}

std::string frame_csv_text(const ParticleFrame& frame) {
  std::ostringstream os;
  os << "x,y,z";
  for (const auto& f : frame.fields) {
    if (f.components == 1)
      os << "," << f.name;
    else
      for (const char* c : {"_x", "_y", "_z"}) os << "," << f.name << c;
  }
  os << "\n";
  const Index n = frame.points();
  for (Index i = 0; i < n; ++i) {
    const std::size_t iu = static_cast<std::size_t>(i);
    os << format_full(frame.positions[3 * iu]) << "," << format_full(frame.positions[3 * iu + 1])
       << "," << format_full(frame.positions[3 * iu + 2]);
    for (const auto& f : frame.fields) {
      const std::size_t nc = static_cast<std::size_t>(f.components);
      for (std::size_t c = 0; c < nc; ++c) os << "," << format_full(f.values[nc * iu + c]);
    }
    os << "\n";
  }
  return os.str();
}

std::string vti_text(const GridFrame& frame) {
  std::ostringstream os;
  const std::string extent =
      "0 " + std::to_string(frame.nx) + " 0 " + std::to_string(frame.ny) + " 0 0";
  os << "<?xml version=\"1.0\"?>\n"
     << "<VTKFile type=\"ImageData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
     << "  <ImageData WholeExtent=\"" << extent << "\" Origin=\"" << format_full(frame.origin_x)
     << " " << format_full(frame.origin_y) << " 0\" Spacing=\"" << format_full(frame.spacing) << " "
     << format_full(frame.spacing) << " " << format_full(frame.spacing) << "\">\n"
     << "    <Piece Extent=\"" << extent << "\">\n"
     << "      <PointData>\n      </PointData>\n      <CellData>\n";
  for (const auto& f : frame.cell_fields) {
    os << "        <DataArray type=\"Float64\" Name=\"" << f.name << "\" NumberOfComponents=\""
       << f.components << "\" format=\"ascii\">";
    for (std::size_t k = 0; k < f.values.size(); ++k)
      os << (k % static_cast<std::size_t>(f.components) ? " " : "\n") << format_full(f.values[k]);
    os << "\n        </DataArray>\n";
  }
  os << "      </CellData>\n    </Piece>\n  </ImageData>\n</VTKFile>\n";
  return os.str();
}

std::string legacy_vtk_grid_text(const GridFrame& frame, double t) {
  std::ostringstream os;
  os << "# vtk DataFile Version 3.0\nstiffbench grid frame t = " << format_full(t)
     << "\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS " << frame.nx + 1 << " " << frame.ny + 1
     << " 1\nORIGIN " << format_full(frame.origin_x) << " " << format_full(frame.origin_y)
     << " 0\nSPACING " << format_full(frame.spacing) << " " << format_full(frame.spacing) << " "
     << format_full(frame.spacing) << "\nCELL_DATA " << frame.cells() << "\n";
  for (const auto& f : frame.cell_fields) {
    if (f.components == 3)
      os << "VECTORS " << f.name << " double\n";
    else
      os << "SCALARS " << f.name << " double 1\nLOOKUP_TABLE default\n";
    const std::size_t nc = static_cast<std::size_t>(f.components);
    for (std::size_t k = 0; k < f.values.size(); ++k)
      os << format_full(f.values[k]) << (k % nc == nc - 1 ? "\n" : " ");
  }
  return os.str();
}

ParticleFrame cell_centres(const GridFrame& frame) {
  ParticleFrame p;
  p.positions.reserve(static_cast<std::size_t>(3 * frame.cells()));
  for (int j = 0; j < frame.ny; ++j)
    for (int i = 0; i < frame.nx; ++i) {
      p.positions.push_back(frame.origin_x + (i + 0.5) * frame.spacing);
      p.positions.push_back(frame.origin_y + (j + 0.5) * frame.spacing);
      p.positions.push_back(0.0);
    }
  p.fields = frame.cell_fields;
  return p;
}

FrameWriter::FrameWriter(const OdeSystem& sys, std::filesystem::path dir, FrameFormat format)
    : sys_(sys), dir_(std::move(dir)), format_(format) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir_, ec);
  require_input(!ec && fs::is_directory(dir_),
                "--out '" + dir_.string() + "': cannot create the output directory" +
                    (ec ? " (" + ec.message() + ")" : std::string()));
  for (auto& q : sys.invariants()) quantities_.push_back(std::move(q));
  for (auto& q : sys.observables()) quantities_.push_back(std::move(q));
  csv_ = "t";
  for (const auto& q : quantities_) {
    columns_.push_back(q.name);
    csv_ += "," + q.name;
  }
  csv_ += "\n";
  // Fail before the run, not at its first frame, when the directory is not writable.
  try {
    write_file_atomic(dir_ / "observables.csv", csv_);
  } catch (const std::exception& e) {
    throw BadInput("--out '" + dir_.string() + "': cannot write into the output directory (" +
                   e.what() + ")");
  }
}

void FrameWriter::write(double t, CVecRef y) {
  csv_ += format_full(t);
  for (const auto& q : quantities_) csv_ += "," + format_full(q.value(t, y));
  csv_ += "\n";
  write_file_atomic(dir_ / "observables.csv", csv_);
  char stem[32];
  std::snprintf(stem, sizeof stem, "frame_%04ld", frames_);
  if (sys_.has_particles() || sys_.has_grid()) {
    const bool grid = sys_.has_grid();
    const std::string name = std::string(stem) + (format_ == FrameFormat::vtk ? ".vtk"
                                                  : grid                      ? ".vti"
                                                                              : ".vtu");
    const GridFrame gframe = grid ? sys_.grid_frame(t, y) : GridFrame{};
    const ParticleFrame frame = grid ? cell_centres(gframe) : sys_.particles(t, y);
    write_file_atomic(dir_ / (std::string(stem) + ".csv"), frame_csv_text(frame));
    if (format_ == FrameFormat::vtk) {
      write_file_atomic(dir_ / name,
                        grid ? legacy_vtk_grid_text(gframe, t) : legacy_vtk_text(frame, t));
    } else {
      write_file_atomic(dir_ / name, grid ? vti_text(gframe) : vtu_text(frame));
      pvd_entries_ +=
          "    <DataSet timestep=\"" + format_full(t) + "\" part=\"0\" file=\"" + name + "\"/>\n";
      write_file_atomic(dir_ / "frames.pvd",
                        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n"
                        "  <Collection>\n" +
                            pvd_entries_ + "  </Collection>\n</VTKFile>\n");
    }
  }
  for (const Profile& p : sys_.profiles(t, y)) {
    std::string text = join(p.columns, ",") + "\n";
    for (const auto& row : p.rows) {
      for (std::size_t c = 0; c < row.size(); ++c) text += (c ? "," : "") + format_full(row[c]);
      text += "\n";
    }
    write_file_atomic(dir_ / (p.name + ".csv"), text);
  }
  ++frames_;
}

}  // namespace stiffbench
