// Reference CSV tables: comments, header, cells kept as text; empty cells (also a trailing one, which
// std::getline does not produce by itself) read as "no number"; a row with the wrong cell count is an
// error naming the file and line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "io/csv_table.hpp"

namespace lamina::io {
namespace {

std::string write(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("lamina_csv_" + name + ".csv");
  std::ofstream(path) << text;
  return path.string();
}

TEST(io_CsvTable, EmptyCellsIncludingATrailingOneAreNoNumbers) {
  const CsvTable t = CsvTable::read(write("sparse", "# source: test\nx,a,b\n1,2,\n3,,4\n5,6,7\n"));
  ASSERT_EQ(t.comments.size(), 1u);
  EXPECT_EQ(t.comments[0], "source: test");
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_EQ(t.number(0, "a"), 2.0);
  EXPECT_FALSE(t.number(0, "b").has_value());
  EXPECT_FALSE(t.number(1, "a").has_value());
  EXPECT_EQ(t.number(1, "b"), 4.0);
  EXPECT_EQ(t.number(2, "b"), 7.0);
  EXPECT_FALSE(t.number(0, "missing").has_value());
  EXPECT_EQ(t.column("b"), 2);
}

TEST(io_CsvTable, WrongCellCountNamesTheLine) {
  try {
    CsvTable::read(write("ragged", "x,a\n1,2\n3,4,5\n"));
    FAIL() << "no error for a ragged row";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(":3: expected 2 cells, found 3"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lamina::io
