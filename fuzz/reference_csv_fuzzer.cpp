// libFuzzer target for the reference-data CSV reader (io::CsvTable, src/io/csv_table.*: the
// validation cases' reference.csv, read by `lamina validate`; see fuzz/README.md).
//
// Each input is written to scratch/reference.csv and read with CsvTable::read; a table is then
// used as `lamina validate` uses it: columns looked up by name, every cell converted with
// number(), rows matched against a cell value.
// Expected outcome: a table whose rows all have the header's cell count, or the documented
// std::runtime_error whose message starts with the file name ("FILE: no header row",
// "FILE:LINE: expected N cells, found M"). Anything else aborts.
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>

#include "fuzz_support.hpp"
#include "io/csv_table.hpp"

namespace {

constexpr const char* kTarget = "reference_csv_fuzzer";

void use(const lamina::io::CsvTable& table) {
  using lamina::fuzz::finding;
  if (table.columns.empty()) finding(kTarget, "a table without columns was returned");
  for (const auto& row : table.rows)
    if (row.size() != table.columns.size()) finding(kTarget, "a row with a cell count different from the header's");
  for (const auto& name : table.columns) {
    const int c = table.column(name);
    if (c < 0 || static_cast<std::size_t>(c) >= table.columns.size() || table.columns[c] != name)
      finding(kTarget, "column('" + name + "') does not find the column");
    for (std::size_t r = 0; r <= table.rows.size(); ++r) (void)table.number(r, name);  // one past the end: nullopt
    std::size_t matches = 0;
    if (!table.rows.empty())
      for (const auto& row : table.rows) matches += row[static_cast<std::size_t>(c)] == table.rows.front()[static_cast<std::size_t>(c)];
    if (!table.rows.empty() && matches == 0) finding(kTarget, "a cell does not match itself");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = lamina::fuzz::write_scratch("reference.csv", data, size);
  try {
    use(lamina::io::CsvTable::read(path));
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).rfind(path + ":", 0) != 0)
      lamina::fuzz::finding(kTarget, std::string("a read error that does not start with the file name: ") + e.what());
  } catch (const std::exception& e) {
    lamina::fuzz::finding(kTarget, std::string("unexpected exception: ") + e.what());
  } catch (...) {
    lamina::fuzz::finding(kTarget, "unexpected non-standard exception");
  }
  return 0;
}
