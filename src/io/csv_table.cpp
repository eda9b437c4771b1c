#include "io/csv_table.hpp"

#include <fmt/format.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace lamina::io {

namespace {
std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  const auto e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}
}  // namespace

CsvTable CsvTable::read(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot open", path));
  CsvTable table;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::string t = trim(line);
    if (t.empty()) continue;
    if (t[0] == '#') {
      table.comments.push_back(trim(t.substr(1)));
      continue;
    }
    std::vector<std::string> cells;
    std::stringstream ss(t);
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(trim(cell));
    if (t.back() == ',') cells.emplace_back();  // a trailing empty cell (getline stops before it)
    if (table.columns.empty()) {
      table.columns = cells;
      continue;
    }
    if (cells.size() != table.columns.size())
      throw std::runtime_error(fmt::format("{}:{}: expected {} cells, found {}", path, number, table.columns.size(), cells.size()));
    table.rows.push_back(cells);
  }
  if (table.columns.empty()) throw std::runtime_error(fmt::format("{}: no header row", path));
  return table;
}

int CsvTable::column(const std::string& name) const {
  for (std::size_t i = 0; i < columns.size(); ++i)
    if (columns[i] == name) return static_cast<int>(i);
  return -1;
}

std::optional<double> CsvTable::number(std::size_t row, const std::string& name) const {
  const int c = column(name);
  if (c < 0 || row >= rows.size()) return std::nullopt;
  try {
    std::size_t used = 0;
    const double v = std::stod(rows[row][static_cast<std::size_t>(c)], &used);
    return v;
  } catch (...) {
    return std::nullopt;
  }
}

}  // namespace lamina::io
