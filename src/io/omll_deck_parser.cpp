// OMLL deck reader, the first half: every command and data row of the deck checked and kept (one line
// per problem with its file:line:column, docs/omll.md), in DeckParser's members.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <optional>
#include <set>
#include <sstream>

#include "io/omll_deck_parser.hpp"

namespace lamina::io::omll_detail {

namespace {

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

}  // namespace

std::string upper(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

OmllCase DeckParser::parse(const std::string& text) {
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

void DeckParser::problem(int line, int column, const std::string& key, const std::string& expected, const std::string& found) {
  problems_.push_back(Diagnostic{file_, line, column, key, expected, found});
}

void DeckParser::problem(const DeckLine& line, std::size_t token, const std::string& expected, const std::string& found) {
  const int column = token < line.tokens.size() ? line.tokens[token].column : line.tokens.back().column;
  problem(line.number, column, line.tokens[0].text, expected, found);
}

bool DeckParser::expect_parameters(const DeckLine& line, std::size_t lower, std::size_t upper, const std::string& what) {
  const std::size_t n = line.tokens.size() - 1;
  if (n >= lower && n <= upper) return true;
  problem(line, std::min(line.tokens.size() - 1, upper + 1), what,
          fmt::format("{} parameter{}", n, n == 1 ? "" : "s"));
  return false;
}

std::optional<Real> DeckParser::real_at(const DeckLine& line, std::size_t i, const std::string& what) {
  auto v = parse_real(line.tokens[i].text);
  if (!v) problem(line, i, what, quoted(line.tokens[i]));
  return v;
}

std::optional<long long> DeckParser::integer_at(const DeckLine& line, std::size_t i, const std::string& what, long long lower) {
  auto v = parse_integer(line.tokens[i].text);
  if (!v || *v < lower) {
    problem(line, i, what, quoted(line.tokens[i]));
    return std::nullopt;
  }
  return v;
}

void DeckParser::declared(const DeckLine& line, std::optional<DeclaredCount>& target, long long lower) {
  if (!expect_parameters(line, 1, 1, "one integer")) return;
  if (auto v = integer_at(line, 1, fmt::format("an integer >= {}", lower), lower))
    target = DeclaredCount{*v, line.number, line.tokens[1].column};
}

void DeckParser::handle(const DeckLine& line) {
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

void DeckParser::data_command(const DeckLine& line) {
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

void DeckParser::batch_command(const DeckLine& line) {
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

void DeckParser::influence_domain(const DeckLine& line) {
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

void DeckParser::material_row(const DeckLine& line) {
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

bool DeckParser::known_material(const DeckLine& line, std::size_t i) {
  for (const auto& m : materials_)
    if (m.name == line.tokens[i].text) return true;
  problem(line, i, "the name of a material defined under MATERIAL", quoted(line.tokens[i]));
  return false;
}

void DeckParser::data_row(const DeckLine& line) {
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

void DeckParser::check_count(const std::optional<DeclaredCount>& declared, std::size_t actual, const std::string& command, const std::string& rows) {
  if (declared && declared->value != static_cast<long long>(actual))
    problem(declared->line, declared->column, command, fmt::format("{} {} (the count given here)", declared->value, rows),
            fmt::format("{} {}", actual, rows));
}

void DeckParser::finish_checks() {
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

}  // namespace lamina::io::omll_detail
