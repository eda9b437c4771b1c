#pragma once
// The OMLL deck reader's internals (seed 004's input format, docs/omll.md): the deck's lines and rows,
// and DeckParser, which checks every command and row (omll_deck_parser.cpp) and converts the deck into a
// lamina case (omll_deck_conversion.cpp). Internal to src/io; the interface is io/omll_deck.hpp.
#include <array>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "core/error.hpp"
#include "core/types.hpp"
#include "io/omll_deck.hpp"

namespace lamina::io::omll_detail {

struct Token {
  std::string text;
  int column = 1;  // 1-based
};

struct DeckLine {
  int number = 0;  // 1-based
  std::vector<Token> tokens;
  std::string upper_command;  // first token in upper case
};

struct NodeRow {
  long long id = 0;
  std::array<std::string, 3> text;  // coordinates as written in the deck
  Vec3 x = Vec3::Zero();
  int line = 0;
};

struct BoundaryRow {
  long long id = 0;
  std::array<bool, 3> prescribed{};
  std::array<std::string, 3> value_text;
  std::array<Real, 3> value{};
  int line = 0;
};

struct LoadRow {
  long long id = 0;
  std::array<std::string, 3> force_text;
  std::array<Real, 3> force{};
  int line = 0;
};

struct CellRow {
  std::array<long long, 8> nodes{};
  int line = 0;
};

struct MaterialRow {
  std::string name;
  std::string E, nu;
  std::optional<std::string> density;
  int line = 0;
  std::array<int, 4> columns{};  // of name, E, nu, density
};

/// A count given by a command (NUMNP 363) and where it was given.
struct DeclaredCount {
  long long value = 0;
  int line = 0;
  int column = 0;
};

/// The text in upper case (OMLL commands are case-insensitive).
std::string upper(std::string text);

/// Reads one deck line by line, keeps what every command and row says and reports every problem
/// (DeckParser::parse throws InputError with all of them), then builds the lamina case.
class DeckParser {
 public:
  explicit DeckParser(std::string file) : file_(std::move(file)) {}

  OmllCase parse(const std::string& text);

 private:
  // ---- parsing (omll_deck_parser.cpp) ----------------------------------------------------------
  enum class Block { none, material, node, boundary, load, evpoint, efgdata, cells };

  void problem(int line, int column, const std::string& key, const std::string& expected, const std::string& found);
  void problem(const DeckLine& line, std::size_t token, const std::string& expected, const std::string& found);
  static std::string quoted(const Token& t) { return "'" + t.text + "'"; }

  /// Exactly `n` parameters after the command (reports otherwise).
  bool expect_parameters(const DeckLine& line, std::size_t lower, std::size_t upper, const std::string& what);
  std::optional<Real> real_at(const DeckLine& line, std::size_t i, const std::string& what);
  std::optional<long long> integer_at(const DeckLine& line, std::size_t i, const std::string& what, long long lower = 0);
  void declared(const DeckLine& line, std::optional<DeclaredCount>& target, long long lower);

  void handle(const DeckLine& line);
  void data_command(const DeckLine& line);

  void batch_command(const DeckLine& line);
  void influence_domain(const DeckLine& line);

  void material_row(const DeckLine& line);
  bool known_material(const DeckLine& line, std::size_t i);

  void data_row(const DeckLine& line);
  void check_count(const std::optional<DeclaredCount>& declared, std::size_t actual, const std::string& command,
                   const std::string& rows);
  void finish_checks();

  // ---- conversion (omll_deck_conversion.cpp) ----------------------------------------------------
  void at(const std::string& key, int line, int column = 1);
  static YAML::Node flow_sequence(const std::vector<std::string>& items);

  static std::string number(Real v) { return fmt::format("{}", v); }

  /// Distinct coordinate levels along each axis (merged within tolerance), ascending.
  std::array<std::vector<Real>, 3> levels(const std::vector<Vec3>& points, Real tolerance) const;
  static int level_index(const std::vector<Real>& levels, Real v, Real tolerance);

  static bool uniform(const std::vector<Real>& levels, Real tolerance);

  /// Selections that pick exactly the nodes `chosen` (indices into nodes_): the union of whole
  /// coordinate planes that lie entirely in the set as one `where`, then `nearest` for the rest.
  std::vector<YAML::Node> selections(const std::set<std::size_t>& chosen) const;
  OmllCase build();

  /// Equal cells of about the size of `count` cells over the nodes' bounding box:
  /// c_d = round(extent_d / h), h = (volume / count)^(1/3).
  std::array<int, 3> estimated_cells(std::size_t count) const;
  void set_cells(YAML::Node& integration, const std::array<int, 3>& cells);

  /// Integration cells: the deck's CELL rows when they tile the nodes' bounding box as a
  /// tensor-product grid (each cell an axis-aligned brick between adjacent corner levels, each
  /// once); otherwise (and for irregular nodes without cells) equal cells of about the same size.
  void convert_cells(YAML::Node& integration, OmllCase& result, Real tolerance, bool nodes_are_grid);

  std::string file_;
  std::vector<Diagnostic> problems_;
  std::map<std::string, std::pair<int, int>> positions_;
  Block block_ = Block::none;
  bool in_batch_ = false, batch_ended_ = false, stopped_ = false;
  int last_line_ = 1, stop_line_ = 0, batch_line_ = 0, node_line_ = 0, efgdata_line_ = 0, title_line_ = 0, support_line_ = 0;
  std::size_t node_rows_at_block_start_ = 0;
  std::string title_;
  std::optional<DeclaredCount> ndm_, numnp_, numev_, ndisp_, nload_, nummat_, ncell_;
  std::vector<MaterialRow> materials_;
  std::vector<NodeRow> nodes_;
  std::map<long long, std::size_t> node_index_;
  std::vector<BoundaryRow> boundary_;
  std::vector<LoadRow> loads_;
  std::vector<CellRow> cells_;
  std::array<std::optional<std::pair<std::string, int>>, 3> gauss_;
  std::optional<std::pair<std::string, int>> basis_, weight_, formulation_, penalty_;
  std::optional<std::string> gauss_beta_;
  std::optional<YAML::Node> support_;
  bool sincheck_ = false;
  std::array<std::vector<Real>, 3> levels_;
  std::vector<std::array<int, 3>> node_level_;
  Real plane_tolerance_ = 1e-9;
};

}  // namespace lamina::io::omll_detail
