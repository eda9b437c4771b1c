#pragma once
// Writes an OutputFrame as a VTK XML UnstructuredGrid (.vtu, base64 binary data) and the
// ParaView collection (.pvd) that lists the frames with their times.
#include <string>
#include <utility>
#include <vector>

#include "core/analysis.hpp"

namespace lamina::io {

void write_vtu(const std::string& path, const OutputFrame& frame);
/// The parallel file (.pvtu) of a frame written as one piece per rank: `frame` gives the field names
/// and sizes (any piece's), `pieces` the piece file names relative to the .pvtu.
void write_pvtu(const std::string& path, const OutputFrame& frame, const std::vector<std::string>& pieces);
/// entries: (time, vtu file name relative to the .pvd)
void write_pvd(const std::string& path, const std::vector<std::pair<Real, std::string>>& entries);

}  // namespace lamina::io
