// OMLL deck reader, the second half: the checked deck converted into a lamina case (the efg method's
// keys: nodes, supports, loads, the integration cells; docs/omll.md "Conversion").
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <optional>
#include <set>
#include <sstream>

#include "io/omll_deck_parser.hpp"

namespace lamina::io::omll_detail {

void DeckParser::at(const std::string& key, int line, int column) {
  if (line > 0) positions_[key] = {line, column};
}

YAML::Node DeckParser::flow_sequence(const std::vector<std::string>& items) {
  YAML::Node s(YAML::NodeType::Sequence);
  for (const auto& item : items) s.push_back(item);
  s.SetStyle(YAML::EmitterStyle::Flow);
  return s;
}

std::array<std::vector<Real>, 3> DeckParser::levels(const std::vector<Vec3>& points, Real tolerance) const {
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

int DeckParser::level_index(const std::vector<Real>& levels, Real v, Real tolerance) {
  auto it = std::lower_bound(levels.begin(), levels.end(), v - tolerance);
  if (it == levels.end() || std::abs(*it - v) > tolerance) return -1;
  return static_cast<int>(it - levels.begin());
}

bool DeckParser::uniform(const std::vector<Real>& levels, Real tolerance) {
  if (levels.size() < 2) return true;
  const Real h = (levels.back() - levels.front()) / static_cast<Real>(levels.size() - 1);
  for (std::size_t i = 0; i < levels.size(); ++i)
    if (std::abs(levels[i] - (levels.front() + h * static_cast<Real>(i))) > tolerance) return false;
  return true;
}

std::vector<YAML::Node> DeckParser::selections(const std::set<std::size_t>& chosen) const {
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

OmllCase DeckParser::build() {
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

std::array<int, 3> DeckParser::estimated_cells(std::size_t count) const {
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

void DeckParser::set_cells(YAML::Node& integration, const std::array<int, 3>& cells) {
  integration["cells"] = flow_sequence({std::to_string(cells[0]), std::to_string(cells[1]), std::to_string(cells[2])});
}

void DeckParser::convert_cells(YAML::Node& integration, OmllCase& result, Real tolerance, bool nodes_are_grid) {
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

}  // namespace lamina::io::omll_detail
