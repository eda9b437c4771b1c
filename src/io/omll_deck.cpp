#include "io/omll_deck.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>

#include "core/error.hpp"
#include "core/types.hpp"

namespace lamina::io {

namespace {

struct Token {
  std::string text;
  int column = 1;  // 1-based
};

struct DeckLine {
  int number = 0;  // 1-based
  std::vector<Token> tokens;
  std::string upper_command;  // first token in upper case
};

std::string upper(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

/// Tokens of a line up to its comment (`%` or `#` start a comment anywhere on the line).
std::vector<Token> tokenize(const std::string& line) {
  std::vector<Token> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    const char c = line[i];
    if (c == '%' || c == '#') break;
    if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
      continue;
    }
    const std::size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i])) && line[i] != '%' && line[i] != '#') ++i;
    tokens.push_back(Token{line.substr(start, i - start), static_cast<int>(start) + 1});
  }
  return tokens;
}

std::optional<Real> parse_real(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (!end || *end != '\0' || !std::isfinite(value)) return std::nullopt;
  if (text.find_first_of("nNiIxX") != std::string::npos) return std::nullopt;  // nan, inf, hex
  return value;
}

std::optional<long long> parse_integer(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const long long value = std::strtoll(text.c_str(), &end, 10);
  if (!end || *end != '\0' || errno == ERANGE) return std::nullopt;
  return value;
}

const std::set<std::string> kDataCommands{"RESULTFILE", "OMLL",     "NDM",   "NUMNP", "NUMEV",      "NDISP",      "NLOAD",
                                          "NUMMAT",     "MATERIAL", "NODE",  "BOUNDARY", "LOAD",    "EVPOINT",    "ENDEVPOINT",
                                          "EFGDATA",    "NCELL",    "NINTX", "NINTY", "NINTZ",      "CELL",       "ENDEFGDATA",
                                          "ENDDATA",    "ECHO",     "ISOELASTIC", "COPY"};
const std::set<std::string> kBatchCommands{"BATCH",   "CHECK",   "MLS",       "BASIS", "WEIGHTFUNCTION", "SINCHECK",
                                           "INFLENCEDOMAIN", "INFLUENCEDOMAIN", "BAND",  "EFGM", "LEASTSQUARE",
                                           "PENALTY", "TIMER",   "TANGENT",   "SOLVE", "OUTPUT", "PRINT", "END"};

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

class DeckParser {
 public:
  explicit DeckParser(std::string file) : file_(std::move(file)) {}

  OmllCase parse(const std::string& text) {
    std::istringstream in(text);
    std::string raw;
    int number = 0;
    while (std::getline(in, raw)) {
      ++number;
      if (!raw.empty() && raw.back() == '\r') raw.pop_back();
      DeckLine line;
      line.number = number;
      line.tokens = tokenize(raw);
      if (line.tokens.empty()) continue;
      line.upper_command = upper(line.tokens[0].text);
      last_line_ = number;
      handle(line);
      if (stopped_) break;
    }
    finish_checks();
    if (!problems_.empty()) throw InputError(problems_);
    return build();
  }

 private:
  enum class Block { none, material, node, boundary, load, evpoint, efgdata, cells };

  void problem(int line, int column, const std::string& key, const std::string& expected, const std::string& found) {
    problems_.push_back(Diagnostic{file_, line, column, key, expected, found});
  }
  void problem(const DeckLine& line, std::size_t token, const std::string& expected, const std::string& found) {
    const int column = token < line.tokens.size() ? line.tokens[token].column : line.tokens.back().column;
    problem(line.number, column, line.tokens[0].text, expected, found);
  }
  static std::string quoted(const Token& t) { return "'" + t.text + "'"; }

  /// Exactly `n` parameters after the command (reports otherwise).
  bool expect_parameters(const DeckLine& line, std::size_t lower, std::size_t upper, const std::string& what) {
    const std::size_t n = line.tokens.size() - 1;
    if (n >= lower && n <= upper) return true;
    problem(line, std::min(line.tokens.size() - 1, upper + 1), what,
            fmt::format("{} parameter{}", n, n == 1 ? "" : "s"));
    return false;
  }

  std::optional<Real> real_at(const DeckLine& line, std::size_t i, const std::string& what) {
    auto v = parse_real(line.tokens[i].text);
    if (!v) problem(line, i, what, quoted(line.tokens[i]));
    return v;
  }
  std::optional<long long> integer_at(const DeckLine& line, std::size_t i, const std::string& what, long long lower = 0) {
    auto v = parse_integer(line.tokens[i].text);
    if (!v || *v < lower) {
      problem(line, i, what, quoted(line.tokens[i]));
      return std::nullopt;
    }
    return v;
  }

  void declared(const DeckLine& line, std::optional<DeclaredCount>& target, long long lower) {
    if (!expect_parameters(line, 1, 1, "one integer")) return;
    if (auto v = integer_at(line, 1, fmt::format("an integer >= {}", lower), lower))
      target = DeclaredCount{*v, line.number, line.tokens[1].column};
  }

  void handle(const DeckLine& line) {
    const std::string& cmd = line.upper_command;
    const bool is_command = kDataCommands.count(cmd) || kBatchCommands.count(cmd) || cmd == "STOP";
    if (!is_command && in_batch_) {
      problem(line, 0, "a batch command (docs/omll.md lists the supported ones)", quoted(line.tokens[0]));
      return;
    }
    if (!is_command) {
      data_row(line);
      return;
    }
    if (cmd == "STOP") {
      stopped_ = true;
      stop_line_ = line.number;
      return;
    }
    if (in_batch_) {
      batch_command(line);
      return;
    }
    if (kBatchCommands.count(cmd) && cmd != "BATCH") {
      problem(line, 0, "a data command (batch commands such as " + line.tokens[0].text + " come after BATCH)",
              quoted(line.tokens[0]));
      return;
    }
    data_command(line);
  }

  void data_command(const DeckLine& line) {
    const std::string& cmd = line.upper_command;
    // commands that live inside a block
    if (cmd == "ISOELASTIC") {
      if (block_ != Block::material) problem(line, 0, "ISOELASTIC inside a MATERIAL block", quoted(line.tokens[0]));
      else material_row(line);
      return;
    }
    if (cmd == "COPY") {
      if (block_ != Block::evpoint) problem(line, 0, "COPY inside an EVPOINT block", quoted(line.tokens[0]));
      else if (line.tokens.size() < 3 || upper(line.tokens[1].text) != "ALL")
        problem(line, 1, "COPY ALL <material> [weight] (evaluation points at all nodes)",
                line.tokens.size() > 1 ? quoted(line.tokens[1]) : "nothing");
      return;
    }
    if (cmd == "NODE" && block_ == Block::node && nodes_.size() == node_rows_at_block_start_) return;  // "NODE" twice
    if (cmd == "NCELL" || cmd == "NINTX" || cmd == "NINTY" || cmd == "NINTZ" || cmd == "CELL" || cmd == "ENDEFGDATA") {
      if (block_ != Block::efgdata && block_ != Block::cells) {
        problem(line, 0, cmd + " inside an EFGDATA block", quoted(line.tokens[0]));
        return;
      }
      if (cmd == "NCELL") declared(line, ncell_, 1);
      else if (cmd == "CELL") {
        if (expect_parameters(line, 1, 1, "CELL NODE (cells given by their 8 node numbers)") &&
            upper(line.tokens[1].text) != "NODE")
          problem(line, 1, "CELL NODE (cells given by their 8 node numbers)", quoted(line.tokens[1]));
        block_ = Block::cells;
      } else if (cmd == "ENDEFGDATA") {
        block_ = Block::none;
      } else {
        const int axis = cmd.back() - 'X';
        if (expect_parameters(line, 1, 1, "a number of Gauss points"))
          if (auto v = integer_at(line, 1, "a number of Gauss points in [1, 20]", 1)) {
            if (*v > 20) problem(line, 1, "a number of Gauss points in [1, 20]", quoted(line.tokens[1]));
            gauss_[static_cast<std::size_t>(axis)] = {line.tokens[1].text, line.number};
          }
      }
      return;
    }
    if (cmd == "ENDEVPOINT") {
      if (block_ != Block::evpoint) problem(line, 0, "ENDEVPOINT after EVPOINT", quoted(line.tokens[0]));
      block_ = Block::none;
      return;
    }
    block_ = Block::none;
    if (cmd == "RESULTFILE") {
      expect_parameters(line, 1, 1, "a result file name");
    } else if (cmd == "OMLL") {
      std::string title;
      for (std::size_t i = 1; i < line.tokens.size(); ++i) title += (i > 1 ? " " : "") + line.tokens[i].text;
      // the seed frames its title with *** ... ***
      while (!title.empty() && (title.front() == '*' || title.front() == ' ')) title.erase(title.begin());
      while (!title.empty() && (title.back() == '*' || title.back() == ' ')) title.pop_back();
      title_ = title;
      title_line_ = line.number;
    } else if (cmd == "NDM") {
      declared(line, ndm_, 1);
      if (ndm_ && ndm_->value != 3) problem(line, 1, "NDM 3 (lamina's efg is a 3D analysis)", quoted(line.tokens[1]));
    } else if (cmd == "NUMNP") {
      declared(line, numnp_, 1);
    } else if (cmd == "NUMEV") {
      declared(line, numev_, 0);
    } else if (cmd == "NDISP") {
      declared(line, ndisp_, 0);
    } else if (cmd == "NLOAD") {
      declared(line, nload_, 0);
    } else if (cmd == "NUMMAT") {
      declared(line, nummat_, 1);
    } else if (cmd == "MATERIAL") {
      block_ = Block::material;
    } else if (cmd == "NODE") {
      block_ = Block::node;
      node_line_ = node_line_ ? node_line_ : line.number;
      node_rows_at_block_start_ = nodes_.size();
    } else if (cmd == "BOUNDARY") {
      block_ = Block::boundary;
    } else if (cmd == "LOAD") {
      block_ = Block::load;
    } else if (cmd == "EVPOINT") {
      block_ = Block::evpoint;
    } else if (cmd == "EFGDATA") {
      block_ = Block::efgdata;
      efgdata_line_ = line.number;
    } else if (cmd == "ENDDATA" || cmd == "ECHO") {
      // end of the domain data / echo of the commands: nothing to do
    } else if (cmd == "BATCH") {
      in_batch_ = true;
      batch_line_ = line.number;
    }
  }

  void batch_command(const DeckLine& line) {
    const std::string& cmd = line.upper_command;
    if (kDataCommands.count(cmd)) {
      problem(line, 0, "a batch command (data commands such as " + line.tokens[0].text + " come before BATCH)",
              quoted(line.tokens[0]));
      return;
    }
    if (cmd == "BATCH") {
      problem(line, 0, "one BATCH ... END section", "a second BATCH");
    } else if (cmd == "END") {
      in_batch_ = false;
      batch_ended_ = true;
    } else if (cmd == "BASIS") {
      if (!expect_parameters(line, 1, 1, "BASIS LINEAR or QUADRIC")) return;
      const std::string b = upper(line.tokens[1].text);
      if (b == "LINEAR") basis_ = {"linear", line.number};
      else if (b == "QUADRIC" || b == "QUADRATIC") basis_ = {"quadratic", line.number};
      else problem(line, 1, "LINEAR or QUADRIC", quoted(line.tokens[1]));
    } else if (cmd == "WEIGHTFUNCTION") {
      if (!expect_parameters(line, 1, 2, "WEIGHTFUNCTION SLS234 | SLS23 | GAUSS [beta]")) return;
      const std::string w = upper(line.tokens[1].text);
      if (w == "SLS234" || w == "SL234") weight_ = {"quartic_spline", line.number};
      else if (w == "SLS23" || w == "SL23" || w == "CUBIC") weight_ = {"cubic_spline", line.number};
      else if (w == "GAUSS") {
        weight_ = {"gauss", line.number};
        if (line.tokens.size() == 3) {
          if (auto beta = real_at(line, 2, "a Gauss weight parameter beta > 0"); beta && *beta > 0)
            gauss_beta_ = line.tokens[2].text;
          else if (beta) problem(line, 2, "a Gauss weight parameter beta > 0", quoted(line.tokens[2]));
        }
      } else {
        problem(line, 1, "SLS234 (quartic spline), SLS23 (cubic spline) or GAUSS", quoted(line.tokens[1]));
      }
      // SLS234's parameter is not used (seed 004: "the parameter after it has no effect")
    } else if (cmd == "SINCHECK") {
      sincheck_ = true;
    } else if (cmd == "INFLENCEDOMAIN" || cmd == "INFLUENCEDOMAIN") {
      influence_domain(line);
    } else if (cmd == "EFGM" || cmd == "LEASTSQUARE") {
      if (formulation_) problem(line, 0, "one of EFGM or LeastSquare", "a second solution method");
      formulation_ = {cmd == "EFGM" ? "galerkin" : "weighted_least_squares", line.number};
    } else if (cmd == "PENALTY") {
      if (!expect_parameters(line, 1, 1, "Penalty <value>")) return;
      if (auto v = real_at(line, 1, "a penalty value > 0"); v) {
        if (*v <= 0) problem(line, 1, "a penalty value > 0", quoted(line.tokens[1]));
        else penalty_ = {line.tokens[1].text, line.number};
      }
    } else if (cmd == "BAND" || cmd == "TIMER" || cmd == "PRINT" || cmd == "CHECK" || cmd == "MLS" || cmd == "TANGENT" ||
               cmd == "SOLVE" || cmd == "OUTPUT") {
      // storage, timing, echo and the solution steps themselves: lamina always assembles,
      // solves and writes its result set (docs/omll.md)
    }
  }

  void influence_domain(const DeckLine& line) {
    if (line.tokens.size() < 2) {
      problem(line, 0, "INFLENCEDOMAIN Fix rx ry rz | Select N | All N [scale] | Variable N [scale]", "no mode");
      return;
    }
    const std::string mode = upper(line.tokens[1].text);
    support_line_ = line.number;
    YAML::Node support(YAML::NodeType::Map);
    if (mode == "FIX" || mode == "FIXED") {
      if (!expect_parameters(line, 4, 4, "INFLENCEDOMAIN Fix rx ry rz")) return;
      YAML::Node radius(YAML::NodeType::Sequence);
      for (std::size_t i = 2; i < 5; ++i) {
        auto r = real_at(line, i, "a support radius > 0");
        if (r && *r <= 0) problem(line, i, "a support radius > 0", quoted(line.tokens[i]));
        radius.push_back(line.tokens[i].text);
      }
      support["radius"] = radius;
    } else if (mode == "SELECT" || mode == "ALL" || mode == "VARIABLE") {
      if (!expect_parameters(line, 2, mode == "SELECT" ? 2 : 3, "INFLENCEDOMAIN " + line.tokens[1].text + " N" +
                                                                    (mode == "SELECT" ? "" : " [scale]")))
        return;
      (void)integer_at(line, 2, "a number of nodes N >= 1", 1);
      if (mode != "SELECT") support["mode"] = mode == "ALL" ? "all" : "variable";
      support["nearest"] = line.tokens[2].text;
      if (line.tokens.size() == 4) {
        (void)real_at(line, 3, "a scale factor");
        support["scale"] = line.tokens[3].text;
      }
    } else {
      problem(line, 1, "Fix, Select, All or Variable", quoted(line.tokens[1]));
      return;
    }
    support_ = support;
  }

  void material_row(const DeckLine& line) {
    if (!expect_parameters(line, 3, 4, "ISOELASTIC <name> <E> <nu> [density]")) return;
    MaterialRow m;
    m.name = line.tokens[1].text;
    m.line = line.number;
    for (std::size_t i = 2; i < line.tokens.size(); ++i) (void)real_at(line, i, "a number");
    m.E = line.tokens[2].text;
    m.nu = line.tokens[3].text;
    if (line.tokens.size() == 5) m.density = line.tokens[4].text;
    for (std::size_t i = 1; i < line.tokens.size(); ++i) m.columns[i - 1] = line.tokens[i].column;
    for (const auto& other : materials_)
      if (other.name == m.name) problem(line, 1, "a unique material name", quoted(line.tokens[1]) + " again");
    materials_.push_back(m);
  }

  bool known_material(const DeckLine& line, std::size_t i) {
    for (const auto& m : materials_)
      if (m.name == line.tokens[i].text) return true;
    problem(line, i, "the name of a material defined under MATERIAL", quoted(line.tokens[i]));
    return false;
  }

  void data_row(const DeckLine& line) {
    switch (block_) {
      case Block::node: {
        if (line.tokens.size() != 4) {
          problem(line, std::min<std::size_t>(line.tokens.size() - 1, 4), "a node row: PointID x y z",
                  fmt::format("{} values", line.tokens.size()));
          return;
        }
        NodeRow row;
        row.line = line.number;
        auto id = integer_at(line, 0, "a node number >= 1 (or an OMLL command)", 1);
        bool ok = id.has_value();
        for (int d = 0; d < 3; ++d) {
          auto v = real_at(line, static_cast<std::size_t>(d) + 1, "a coordinate (finite number)");
          if (v) row.x[d] = *v, row.text[static_cast<std::size_t>(d)] = line.tokens[static_cast<std::size_t>(d) + 1].text;
          else ok = false;
        }
        if (!ok) return;
        row.id = *id;
        if (!node_index_.emplace(row.id, nodes_.size()).second) {
          problem(line, 0, "each node number once", fmt::format("node {} again", row.id));
          return;
        }
        nodes_.push_back(row);
        return;
      }
      case Block::boundary: {
        if (line.tokens.size() != 8) {
          problem(line, std::min<std::size_t>(line.tokens.size() - 1, 8),
                  "a boundary row: PointID material idx idy idz u v w", fmt::format("{} values", line.tokens.size()));
          return;
        }
        BoundaryRow row;
        row.line = line.number;
        auto id = integer_at(line, 0, "a node number >= 1 (or an OMLL command)", 1);
        bool ok = id.has_value() && known_material(line, 1);
        for (int d = 0; d < 3; ++d) {
          const std::size_t i = 2 + static_cast<std::size_t>(d);
          auto flag = parse_integer(line.tokens[i].text);
          if (!flag || (*flag != 0 && *flag != 1)) {
            problem(line, i, "a flag 0 (displacement prescribed) or 1 (free)", quoted(line.tokens[i]));
            ok = false;
            continue;
          }
          row.prescribed[static_cast<std::size_t>(d)] = *flag == 0;
          auto v = real_at(line, 5 + static_cast<std::size_t>(d), "a prescribed displacement (finite number)");
          if (v) row.value[static_cast<std::size_t>(d)] = *v, row.value_text[static_cast<std::size_t>(d)] = line.tokens[5 + static_cast<std::size_t>(d)].text;
          else ok = false;
        }
        if (ok) {
          row.id = *id;
          boundary_.push_back(row);
        }
        return;
      }
      case Block::load: {
        if (line.tokens.size() != 11) {
          problem(line, std::min<std::size_t>(line.tokens.size() - 1, 11),
                  "a load row: PointID material idx idy idz nx ny nz fx fy fz", fmt::format("{} values", line.tokens.size()));
          return;
        }
        LoadRow row;
        row.line = line.number;
        auto id = integer_at(line, 0, "a node number >= 1 (or an OMLL command)", 1);
        bool ok = id.has_value() && known_material(line, 1);
        for (std::size_t i = 2; i < 5; ++i)
          if (!parse_integer(line.tokens[i].text)) ok = false, problem(line, i, "an integer flag", quoted(line.tokens[i]));
        for (std::size_t i = 5; i < 11; ++i)
          if (!real_at(line, i, "a finite number")) ok = false;
        if (!ok) return;
        row.id = *id;
        for (std::size_t d = 0; d < 3; ++d) {
          row.force_text[d] = line.tokens[8 + d].text;
          row.force[d] = *parse_real(row.force_text[d]);
        }
        loads_.push_back(row);
        return;
      }
      case Block::cells: {
        CellRow row;
        row.line = line.number;
        std::size_t first = 0;
        if (!parse_integer(line.tokens[0].text)) {
          if (!known_material(line, 0)) return;
          first = 1;
        }
        if (line.tokens.size() - first != 8) {
          problem(line, line.tokens.size() - 1, "a cell row: [material] and 8 node numbers",
                  fmt::format("{} node numbers", line.tokens.size() - first));
          return;
        }
        for (std::size_t k = 0; k < 8; ++k) {
          auto id = integer_at(line, first + k, "a node number >= 1", 1);
          if (!id) return;
          row.nodes[k] = *id;
        }
        cells_.push_back(row);
        return;
      }
      default:
        break;
    }
    if (block_ == Block::material || block_ == Block::evpoint || block_ == Block::efgdata)
      problem(line, 0, "a command of this block", quoted(line.tokens[0]));
    else
      problem(line, 0, "an OMLL command (docs/omll.md lists the supported ones)", quoted(line.tokens[0]));
  }

  void check_count(const std::optional<DeclaredCount>& declared, std::size_t actual, const std::string& command,
                   const std::string& rows) {
    if (declared && declared->value != static_cast<long long>(actual))
      problem(declared->line, declared->column, command, fmt::format("{} {} (the count given here)", declared->value, rows),
              fmt::format("{} {}", actual, rows));
  }

  void finish_checks() {
    if (!stopped_) problem(last_line_, 1, "STOP", "STOP at the end of the deck", "the end of the file without STOP");
    if (!batch_line_) problem(last_line_, 1, "BATCH", "a BATCH ... END section (solution commands)", "none");
    else if (!batch_ended_ && stopped_) problem(stop_line_, 1, "END", "END closing the BATCH section before STOP", "STOP");
    if (nodes_.empty()) problem(node_line_ ? node_line_ : last_line_, 1, "NODE", "node rows: PointID x y z", "none");
    if (materials_.empty()) problem(last_line_, 1, "MATERIAL", "a MATERIAL block with an ISOELASTIC row", "none");
    if (materials_.size() > 1)
      problem(materials_[1].line, 1, "ISOELASTIC",
              "one material (a deck with several: write the lamina case with materials assigned by where/select)",
              fmt::format("{} materials", materials_.size()));
    check_count(numnp_, nodes_.size(), "NUMNP", "nodes");
    check_count(nummat_, materials_.size(), "NUMMAT", "materials");
    check_count(ndisp_, boundary_.size(), "NDISP", "boundary rows");
    check_count(nload_, loads_.size(), "NLOAD", "load rows");
    check_count(ncell_, cells_.size(), "NCELL", "cells");
    auto known_node = [&](long long id, int line) {
      if (node_index_.count(id)) return true;
      problem(line, 1, "node", "a node number defined under NODE", std::to_string(id));
      return false;
    };
    for (const auto& b : boundary_) (void)known_node(b.id, b.line);
    for (const auto& l : loads_) (void)known_node(l.id, l.line);
    for (const auto& c : cells_)
      for (long long id : c.nodes)
        if (!known_node(id, c.line)) break;
  }

  // ---- conversion -------------------------------------------------------------------------

  void at(const std::string& key, int line, int column = 1) {
    if (line > 0) positions_[key] = {line, column};
  }

  static YAML::Node flow_sequence(const std::vector<std::string>& items) {
    YAML::Node s(YAML::NodeType::Sequence);
    for (const auto& item : items) s.push_back(item);
    s.SetStyle(YAML::EmitterStyle::Flow);
    return s;
  }

  static std::string number(Real v) { return fmt::format("{}", v); }

  /// Distinct coordinate levels along each axis (merged within tolerance), ascending.
  std::array<std::vector<Real>, 3> levels(const std::vector<Vec3>& points, Real tolerance) const {
    std::array<std::vector<Real>, 3> out;
    for (int d = 0; d < 3; ++d) {
      std::vector<Real> values;
      for (const auto& p : points) values.push_back(p[d]);
      std::sort(values.begin(), values.end());
      for (Real v : values)
        if (out[static_cast<std::size_t>(d)].empty() || v - out[static_cast<std::size_t>(d)].back() > tolerance)
          out[static_cast<std::size_t>(d)].push_back(v);
    }
    return out;
  }

  static int level_index(const std::vector<Real>& levels, Real v, Real tolerance) {
    auto it = std::lower_bound(levels.begin(), levels.end(), v - tolerance);
    if (it == levels.end() || std::abs(*it - v) > tolerance) return -1;
    return static_cast<int>(it - levels.begin());
  }

  static bool uniform(const std::vector<Real>& levels, Real tolerance) {
    if (levels.size() < 2) return true;
    const Real h = (levels.back() - levels.front()) / static_cast<Real>(levels.size() - 1);
    for (std::size_t i = 0; i < levels.size(); ++i)
      if (std::abs(levels[i] - (levels.front() + h * static_cast<Real>(i))) > tolerance) return false;
    return true;
  }

  /// Selections that pick exactly the nodes `chosen` (indices into nodes_): the union of whole
  /// coordinate planes that lie entirely in the set as one `where`, then `nearest` for the rest.
  std::vector<YAML::Node> selections(const std::set<std::size_t>& chosen) const {
    std::vector<YAML::Node> out;
    if (chosen.size() == nodes_.size()) {
      out.emplace_back("all");
      return out;
    }
    std::set<std::size_t> covered;
    std::vector<std::string> terms;
    const char* names[3] = {"x", "y", "z"};
    for (int d = 0; d < 3; ++d) {
      for (std::size_t level = 0; level < levels_[static_cast<std::size_t>(d)].size(); ++level) {
        std::vector<std::size_t> members;
        bool inside = true;
        for (std::size_t i = 0; i < nodes_.size() && inside; ++i)
          if (node_level_[i][static_cast<std::size_t>(d)] == static_cast<int>(level)) {
            members.push_back(i);
            inside = chosen.count(i) > 0;
          }
        if (!inside || members.size() < 2) continue;
        bool adds = false;
        for (std::size_t i : members) adds |= covered.insert(i).second;
        if (adds)
          terms.push_back(fmt::format("abs({} - {}) < {}", names[d], number(levels_[static_cast<std::size_t>(d)][level]),
                                      number(plane_tolerance_)));
      }
    }
    if (!terms.empty()) {
      std::string where;
      for (const auto& t : terms) where += (where.empty() ? "" : " or ") + t;
      YAML::Node s(YAML::NodeType::Map);
      s["where"] = where;
      s.SetStyle(YAML::EmitterStyle::Flow);
      out.push_back(s);
    }
    for (std::size_t i : chosen) {
      if (covered.count(i)) continue;
      YAML::Node s(YAML::NodeType::Map);
      s["nearest"] = flow_sequence({nodes_[i].text[0], nodes_[i].text[1], nodes_[i].text[2]});
      s.SetStyle(YAML::EmitterStyle::Flow);
      out.push_back(s);
    }
    return out;
  }

  OmllCase build() {
    OmllCase result;
    YAML::Node doc(YAML::NodeType::Map);
    const std::string stem = std::filesystem::path(file_).stem().string();
    doc["title"] = title_.empty() ? stem : title_;
    at("title", title_line_);
    doc["method"] = "efg";
    at("method", batch_line_);

    // materials
    const MaterialRow& m = materials_.front();
    YAML::Node material(YAML::NodeType::Map);
    material["name"] = m.name;
    material["model"] = "linear_elastic";
    material["E"] = m.E;
    material["nu"] = m.nu;
    if (m.density) material["density"] = *m.density;
    material.SetStyle(YAML::EmitterStyle::Flow);
    doc["materials"].push_back(material);
    at("materials.0", m.line);
    at("materials.0.name", m.line, m.columns[0]);
    at("materials.0.E", m.line, m.columns[1]);
    at("materials.0.nu", m.line, m.columns[2]);
    if (m.density) at("materials.0.density", m.line, m.columns[3]);

    // geometry: the bounding box of the nodes
    std::vector<Vec3> points;
    for (const auto& n : nodes_) points.push_back(n.x);
    Vec3 lo = points.front(), hi = points.front();
    std::array<std::string, 3> lo_text = nodes_.front().text, hi_text = nodes_.front().text;
    for (const auto& n : nodes_)
      for (int d = 0; d < 3; ++d) {
        if (n.x[d] < lo[d]) lo[d] = n.x[d], lo_text[static_cast<std::size_t>(d)] = n.text[static_cast<std::size_t>(d)];
        if (n.x[d] > hi[d]) hi[d] = n.x[d], hi_text[static_cast<std::size_t>(d)] = n.text[static_cast<std::size_t>(d)];
      }
    const Real diagonal = (hi - lo).norm();
    const Real tolerance = 1e-7 * std::max(diagonal, 1e-300);
    levels_ = levels(points, tolerance);
    node_level_.resize(nodes_.size());
    for (std::size_t i = 0; i < nodes_.size(); ++i)
      for (int d = 0; d < 3; ++d)
        node_level_[i][static_cast<std::size_t>(d)] = level_index(levels_[static_cast<std::size_t>(d)], nodes_[i].x[d], tolerance);
    Real smallest_gap = diagonal;
    for (const auto& axis : levels_)
      for (std::size_t i = 1; i < axis.size(); ++i) smallest_gap = std::min(smallest_gap, axis[i] - axis[i - 1]);
    plane_tolerance_ = std::min(1e-6 * std::max(diagonal, 1e-300), 0.25 * smallest_gap);
    plane_tolerance_ = std::stod(fmt::format("{:.2g}", plane_tolerance_));

    YAML::Node geometry(YAML::NodeType::Map);
    geometry["type"] = "box";
    geometry["min"] = flow_sequence({lo_text[0], lo_text[1], lo_text[2]});
    geometry["max"] = flow_sequence({hi_text[0], hi_text[1], hi_text[2]});
    doc["geometry"] = geometry;
    at("geometry", node_line_);
    for (int d = 0; d < 3; ++d)
      if (!(hi[d] > lo[d]))
        problems_.push_back(Diagnostic{file_, node_line_, 1, "NODE",
                                       "nodes spanning a 3D body (lamina's geometry is their bounding box)",
                                       fmt::format("all nodes at {} = {}", "xyz"[d], number(lo[d]))});

    // discretization: a structured grid when the nodes are one, else the coordinates
    YAML::Node discretization(YAML::NodeType::Map);
    bool grid = true;
    std::set<std::array<int, 3>> occupied;
    for (std::size_t i = 0; i < nodes_.size(); ++i) grid &= occupied.insert(node_level_[i]).second;
    std::size_t grid_count = 1;
    for (const auto& axis : levels_) grid_count *= axis.size();
    grid &= grid_count == nodes_.size();
    for (const auto& axis : levels_) grid &= uniform(axis, tolerance) && axis.size() >= 2;
    if (grid) {
      discretization["nodes"] = flow_sequence({std::to_string(levels_[0].size()), std::to_string(levels_[1].size()),
                                               std::to_string(levels_[2].size())});
      result.notes.push_back(fmt::format("the {} nodes form the uniform {} x {} x {} grid of their bounding box: "
                                         "discretization.nodes gives the counts",
                                         nodes_.size(), levels_[0].size(), levels_[1].size(), levels_[2].size()));
    } else {
      YAML::Node list(YAML::NodeType::Sequence);
      for (const auto& n : nodes_) list.push_back(flow_sequence({n.text[0], n.text[1], n.text[2]}));
      discretization["nodes"]["coordinates"] = list;
    }
    doc["discretization"] = discretization;
    at("discretization", node_line_);
    at("discretization.nodes", node_line_);

    // boundary: per component and prescribed value, the nodes as whole planes + single nodes
    YAML::Node boundary(YAML::NodeType::Sequence);
    {
      struct Group {
        int component;
        Real value;
        std::string text;
        std::set<std::size_t> nodes;
        int line;
      };
      std::vector<Group> groups;
      for (const auto& b : boundary_) {
        for (int d = 0; d < 3; ++d) {
          if (!b.prescribed[static_cast<std::size_t>(d)]) continue;
          const Real v = b.value[static_cast<std::size_t>(d)];
          auto g = std::find_if(groups.begin(), groups.end(), [&](const Group& x) { return x.component == d && x.value == v; });
          if (g == groups.end()) groups.push_back(Group{d, v, b.value_text[static_cast<std::size_t>(d)], {}, b.line}), g = groups.end() - 1;
          g->nodes.insert(node_index_.at(b.id));
        }
      }
      const char* names[3] = {"x", "y", "z"};
      for (const auto& g : groups) {
        for (const auto& select : selections(g.nodes)) {
          YAML::Node entry(YAML::NodeType::Map);
          entry["select"] = select;
          if (g.value == 0.0) {
            entry["fix"] = flow_sequence({names[g.component]});
          } else {
            YAML::Node displacement(YAML::NodeType::Map);
            displacement[names[g.component]] = g.text;
            displacement.SetStyle(YAML::EmitterStyle::Flow);
            entry["displacement"] = displacement;
          }
          entry.SetStyle(YAML::EmitterStyle::Flow);
          at(fmt::format("boundary.{}", boundary.size()), g.line);
          boundary.push_back(entry);
        }
      }
    }
    if (boundary.size() > 0) doc["boundary"] = boundary;

    // loads: point forces at their nodes; probes: the displacement there
    YAML::Node loads(YAML::NodeType::Sequence), probes(YAML::NodeType::Sequence);
    std::set<std::string> probe_names;
    for (const auto& l : loads_) {
      const NodeRow& n = nodes_[node_index_.at(l.id)];
      YAML::Node entry(YAML::NodeType::Map);
      YAML::Node select(YAML::NodeType::Map);
      select["nearest"] = flow_sequence({n.text[0], n.text[1], n.text[2]});
      select.SetStyle(YAML::EmitterStyle::Flow);
      entry["select"] = select;
      entry["force"] = flow_sequence({l.force_text[0], l.force_text[1], l.force_text[2]});
      entry.SetStyle(YAML::EmitterStyle::Flow);
      at(fmt::format("loads.{}", loads.size()), l.line);
      loads.push_back(entry);
      for (int d = 0; d < 3; ++d) {
        if (l.force[static_cast<std::size_t>(d)] == 0.0) continue;
        const std::string name = fmt::format("u{}_{}", l.id, "xyz"[d]);
        if (!probe_names.insert(name).second) continue;
        YAML::Node probe(YAML::NodeType::Map);
        probe["name"] = name;
        probe["field"] = "displacement";
        probe["component"] = std::string(1, "xyz"[d]);
        probe["at"] = flow_sequence({n.text[0], n.text[1], n.text[2]});
        probe.SetStyle(YAML::EmitterStyle::Flow);
        at(fmt::format("probes.{}", probes.size()), l.line);
        probes.push_back(probe);
      }
    }
    if (loads.size() > 0) doc["loads"] = loads;

    // efg section
    YAML::Node efg(YAML::NodeType::Map);
    efg["formulation"] = formulation_ ? formulation_->first : std::string("galerkin");
    if (formulation_) at("efg.formulation", formulation_->second);
    if (basis_) efg["basis"] = basis_->first, at("efg.basis", basis_->second);
    if (weight_) efg["weight"] = weight_->first, at("efg.weight", weight_->second);
    if (gauss_beta_) efg["gauss_beta"] = *gauss_beta_, at("efg.gauss_beta", weight_->second);
    if (support_) {
      support_->SetStyle(YAML::EmitterStyle::Flow);
      efg["support"] = *support_;
      at("efg.support", support_line_);
    }
    if (sincheck_) efg["singular_remedy"] = "true";
    YAML::Node integration(YAML::NodeType::Map);
    convert_cells(integration, result, tolerance, grid);
    if (gauss_[0] || gauss_[1] || gauss_[2]) {
      std::vector<std::string> g;
      for (const auto& axis : gauss_) g.push_back(axis ? axis->first : std::string("2"));
      integration["gauss"] = flow_sequence(g);
      for (const auto& axis : gauss_)
        if (axis) at("efg.integration.gauss", axis->second);
    }
    if (integration.size() > 0) {
      integration.SetStyle(YAML::EmitterStyle::Flow);
      efg["integration"] = integration;
      at("efg.integration", efgdata_line_);
    }
    const bool least_squares = formulation_ && formulation_->first == "weighted_least_squares";
    if (least_squares) {
      // seed 004: WLSM's penalty beta (the equilibrium weight); alpha = beta (E / (1 - nu^2))^2 by default
      if (penalty_) {
        YAML::Node wlsm(YAML::NodeType::Map);
        wlsm["traction_weight"] = penalty_->first;
        wlsm.SetStyle(YAML::EmitterStyle::Flow);
        efg["weighted_least_squares"] = wlsm;
        at("efg.weighted_least_squares", penalty_->second);
      }
    } else {
      // OMLL imposes the boundary rows by a penalty at those nodes: lamina's penalty_nodes
      efg["essential_bc"] = "penalty_nodes";
      if (penalty_) efg["penalty"] = penalty_->first, at("efg.penalty", penalty_->second);
    }
    doc["efg"] = efg;
    at("efg", batch_line_);
    if (probes.size() > 0) doc["probes"] = probes;

    if (!problems_.empty()) throw InputError(problems_);
    result.document = doc;
    result.positions = positions_;
    return result;
  }

  /// Equal cells of about the size of `count` cells over the nodes' bounding box:
  /// c_d = round(extent_d / h), h = (volume / count)^(1/3).
  std::array<int, 3> estimated_cells(std::size_t count) const {
    std::array<Real, 3> extent{};
    Real volume = 1.0;
    for (std::size_t d = 0; d < 3; ++d) {
      extent[d] = levels_[d].back() - levels_[d].front();
      volume *= extent[d];
    }
    const Real h = std::cbrt(volume / static_cast<Real>(std::max<std::size_t>(count, 1)));
    std::array<int, 3> cells{};
    for (std::size_t d = 0; d < 3; ++d) cells[d] = std::max(1, static_cast<int>(std::lround(extent[d] / h)));
    return cells;
  }

  void set_cells(YAML::Node& integration, const std::array<int, 3>& cells) {
    integration["cells"] = flow_sequence({std::to_string(cells[0]), std::to_string(cells[1]), std::to_string(cells[2])});
  }

  /// Integration cells: the deck's CELL rows when they tile the nodes' bounding box as a
  /// tensor-product grid (each cell an axis-aligned brick between adjacent corner levels, each
  /// once); otherwise (and for irregular nodes without cells) equal cells of about the same size.
  void convert_cells(YAML::Node& integration, OmllCase& result, Real tolerance, bool nodes_are_grid) {
    if (cells_.empty()) {
      if (nodes_are_grid) return;  // lamina derives one cell per node interval, as a YAML case would
      const auto cells = estimated_cells(nodes_.size());
      set_cells(integration, cells);
      result.notes.push_back(fmt::format(
          "approximation: the deck gives no cells and its nodes are not a grid: {} x {} x {} equal background cells "
          "(about one per node)", cells[0], cells[1], cells[2]));
      return;
    }
    for (const auto& c : cells_) {
      std::set<long long> distinct(c.nodes.begin(), c.nodes.end());
      if (distinct.size() != 8)
        problems_.push_back(Diagnostic{file_, c.line, 1, "CELL", "8 different corner node numbers", "a node number twice"});
    }
    if (!problems_.empty()) return;
    std::vector<Vec3> corners;
    for (const auto& c : cells_)
      for (long long id : c.nodes) corners.push_back(nodes_[node_index_.at(id)].x);
    const auto cell_levels = levels(corners, tolerance);
    std::set<std::array<int, 3>> seen;
    bool tensor_grid = true;
    for (const auto& c : cells_) {
      constexpr int kLarge = std::numeric_limits<int>::max();
      std::array<int, 3> lower{kLarge, kLarge, kLarge}, upper{-1, -1, -1};
      std::set<std::array<int, 3>> corner_set;
      for (long long id : c.nodes) {
        std::array<int, 3> index{};
        for (std::size_t d = 0; d < 3; ++d) {
          index[d] = level_index(cell_levels[d], nodes_[node_index_.at(id)].x[static_cast<int>(d)], tolerance);
          lower[d] = std::min(lower[d], index[d]);
          upper[d] = std::max(upper[d], index[d]);
        }
        corner_set.insert(index);
      }
      bool brick = corner_set.size() == 8;
      for (std::size_t d = 0; d < 3; ++d) brick &= upper[d] == lower[d] + 1;
      tensor_grid &= brick && seen.insert(lower).second;
    }
    std::size_t expected = 1;
    for (const auto& axis : cell_levels) expected *= axis.size() - 1;
    for (std::size_t d = 0; d < 3; ++d)
      tensor_grid &= std::abs(cell_levels[d].front() - levels_[d].front()) <= tolerance &&
                     std::abs(cell_levels[d].back() - levels_[d].back()) <= tolerance;
    tensor_grid &= seen.size() == expected;
    at("efg.integration.cells", cells_.front().line);
    if (!tensor_grid) {
      const auto cells = estimated_cells(cells_.size());
      set_cells(integration, cells);
      result.notes.push_back(fmt::format(
          "approximation: the deck's {} cells are not a tensor-product grid of the nodes' bounding box; lamina uses "
          "{} x {} x {} equal background cells of about the same size",
          cells_.size(), cells[0], cells[1], cells[2]));
      return;
    }
    set_cells(integration, {static_cast<int>(cell_levels[0].size() - 1), static_cast<int>(cell_levels[1].size() - 1),
                            static_cast<int>(cell_levels[2].size() - 1)});
    for (const auto& axis : cell_levels)
      if (!uniform(axis, tolerance)) {
        result.notes.push_back(
            "approximation: the deck's cells are not equally spaced; lamina uses the same number of equal cells per direction");
        break;
      }
  }

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

}  // namespace

bool is_omll_deck(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  return upper(extension) == ".OMLL";
}

OmllCase parse_omll_deck(const std::string& text, const std::string& file) { return DeckParser(file).parse(text); }

OmllCase read_omll_deck(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(Diagnostic{path, 0, 0, "<file>", "a readable OMLL deck", "'" + path + "' cannot be opened"});
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse_omll_deck(buffer.str(), path);
}

std::string omll_case_yaml(const OmllCase& converted, const std::string& deck_path) {
  YAML::Emitter out;
  out.SetIndent(2);
  out << converted.document;  // lists of numbers and list entries carry flow style: one line each
  std::string text = fmt::format("# lamina case converted from the OMLL deck {} (lamina convert; docs/omll.md)\n", deck_path);
  for (const auto& note : converted.notes) text += "# " + note + "\n";
  text += out.c_str();
  text += "\n";
  return text;
}

}  // namespace lamina::io
