#pragma once
// A small CSV table with a header row: '#' lines are comments (e.g. "# source: ..."), cells are
// kept as text and converted on demand. Used for reference data.
#include <optional>
#include <string>
#include <vector>

namespace lamina::io {

struct CsvTable {
  std::vector<std::string> comments;  // text of the '#' lines, without the '#'
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;

  /// Throws std::runtime_error with file:line for malformed files.
  static CsvTable read(const std::string& path);
  int column(const std::string& name) const;  // -1 if absent
  std::optional<double> number(std::size_t row, const std::string& name) const;
};

}  // namespace lamina::io
