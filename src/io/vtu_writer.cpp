#include "io/vtu_writer.hpp"

#include <fmt/format.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace lamina::io {

namespace {

std::string base64(const unsigned char* data, std::size_t size) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve(4 * ((size + 2) / 3));
  std::size_t i = 0;
  for (; i + 2 < size; i += 3) {
    const unsigned v = (data[i] << 16) | (data[i + 1] << 8) | data[i + 2];
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += table[(v >> 6) & 63];
    out += table[v & 63];
  }
  if (i < size) {
    unsigned v = data[i] << 16;
    if (i + 1 < size) v |= data[i + 1] << 8;
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += (i + 1 < size) ? table[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

/// VTK binary inline data: a UInt32 byte count followed by the payload, base64 encoded together.
template <typename T>
std::string encode(const std::vector<T>& values) {
  const std::uint32_t bytes = static_cast<std::uint32_t>(values.size() * sizeof(T));
  std::vector<unsigned char> buffer(sizeof(std::uint32_t) + bytes);
  std::memcpy(buffer.data(), &bytes, sizeof(bytes));
  if (bytes) std::memcpy(buffer.data() + sizeof(bytes), values.data(), bytes);
  return base64(buffer.data(), buffer.size());
}

const char* vtk_type(const double*) { return "Float64"; }
const char* vtk_type(const std::int64_t*) { return "Int64"; }
const char* vtk_type(const std::uint8_t*) { return "UInt8"; }

template <typename T>
void data_array(std::ofstream& out, const std::string& name, int components, const std::vector<T>& values) {
  out << fmt::format("        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"binary\">\n",
                     vtk_type(static_cast<const T*>(nullptr)), name, components);
  out << "          " << encode(values) << "\n        </DataArray>\n";
}

}  // namespace

void write_vtu(const std::string& path, const OutputFrame& frame) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  const Index n = frame.points.cols();
  const int nv = std::max(1, frame.cell_vertices);
  const Index cells = nv == 1 ? n : static_cast<Index>(frame.cell_connectivity.size()) / nv;
  out << "<?xml version=\"1.0\"?>\n"
         "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt32\">\n"
         "  <UnstructuredGrid>\n";
  out << fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", n, cells);
  out << "      <PointData>\n";
  for (const auto& field : frame.point_fields) {
    if (static_cast<Index>(field.values.size()) != n * field.components)
      throw std::logic_error("field " + field.name + " has the wrong size");
    // Symmetric tensors are written as 6 components in VTK's order xx yy zz xy yz xz.
    data_array(out, field.name, field.components, field.values);
  }
  out << "      </PointData>\n      <Points>\n";
  std::vector<double> coordinates(frame.points.data(), frame.points.data() + 3 * n);
  data_array(out, "Points", 3, coordinates);
  out << "      </Points>\n      <Cells>\n";
  std::vector<std::int64_t> connectivity, offsets;
  std::vector<std::uint8_t> types;
  const std::uint8_t type = nv == 1 ? 1 : nv == 4 ? 9 : nv == 8 ? 12 : 2;
  if (nv == 1) {
    for (Index i = 0; i < n; ++i) connectivity.push_back(i);
  } else {
    connectivity.assign(frame.cell_connectivity.begin(), frame.cell_connectivity.end());
  }
  for (Index c = 0; c < cells; ++c) {
    offsets.push_back((c + 1) * nv);
    types.push_back(type);
  }
  data_array(out, "connectivity", 1, connectivity);
  data_array(out, "offsets", 1, offsets);
  data_array(out, "types", 1, types);
  out << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  if (!out) throw std::runtime_error("error while writing " + path);
}

void write_pvtu(const std::string& path, const OutputFrame& frame, const std::vector<std::string>& pieces) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "<?xml version=\"1.0\"?>\n"
         "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt32\">\n"
         "  <PUnstructuredGrid GhostLevel=\"0\">\n    <PPointData>\n";
  for (const auto& field : frame.point_fields)
    out << fmt::format("      <PDataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\"/>\n", field.name,
                       field.components);
  out << "    </PPointData>\n    <PPoints>\n      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n"
         "    </PPoints>\n";
  for (const auto& piece : pieces) out << fmt::format("    <Piece Source=\"{}\"/>\n", piece);
  out << "  </PUnstructuredGrid>\n</VTKFile>\n";
  if (!out) throw std::runtime_error("error while writing " + path);
}

void write_pvd(const std::string& path, const std::vector<std::pair<Real, std::string>>& entries) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (const auto& [time, file] : entries)
    out << fmt::format("    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", time, file);
  out << "  </Collection>\n</VTKFile>\n";
}

}  // namespace lamina::io
