// OMLL macro decks (io/omll_deck.hpp): parsing, the case they convert to, diagnostics with deck
// lines, and `lamina convert` + `lamina run` of the example giving the same probe as the deck.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "io/omll_deck.hpp"

namespace lamina::io {
namespace {

/// A small valid deck: 3 x 2 x 2 nodes on [0,2]x[0,1]x[0,1], clamped at x = 0, a load at x = 2.
std::string small_deck(const std::string& method = "EFGM", const std::string& extra_batch = "") {
  std::ostringstream d;
  d << "RESULTFILE SMALL.RES % comment\n"
    << "OMLL *** small bar *** % title\n"
    << "NDM 3\nNUMNP 12\nNUMEV 12\nNDISP 4\nNLOAD 1\nNUMMAT 1\n"
    << "MATERIAL\nISOELASTIC Steel 200.0 0.25\n"
    << "NODE\nNODE\n# PointID x y z\n";
  int id = 1;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i) d << id++ << " " << i << ".0 " << j << ".0 " << k << ".0\n";
  d << "BOUNDARY\n";
  for (int n : {1, 4, 7, 10}) d << n << " Steel 0 0 0 0.0 0.0 0.0\n";
  d << "LOAD\n3 Steel 0 0 0 0 0 1 0.0 0.0 -1.5  # at (2, 0, 0)\n"
    << "EVPOINT\nCOPY ALL Steel 1.0\nENDEVPOINT\n"
    << "EFGDATA\nNCELL 2\nNINTX 2\nNINTY 2\nNINTZ 3\nCELL NODE\n"
    << "Steel 1 2 5 4 7 8 11 10\nSteel 2 3 6 5 8 9 12 11\nENDEFGDATA\nENDDATA\n"
    << "BATCH\nMLS\nBASIS LINEAR\nWEIGHTFUNCTION GAUSS 2.5\nINFLENCEDOMAIN Fix 1.5 1.5 1.5\n"
    << method << "\nPenalty 1.0e7\n" << extra_batch << "SOLVE\nEND\nSTOP\ntext after STOP is not read\n";
  return d.str();
}

std::vector<Diagnostic> problems_of(const std::string& text) {
  try {
    (void)parse_omll_deck(text, "deck.omll");
  } catch (const InputError& e) {
    return e.diagnostics();
  }
  return {};
}

TEST(io_omll_deck, converts_a_small_deck_to_an_efg_case) {
  const OmllCase c = parse_omll_deck(small_deck(), "small.omll");
  const YAML::Node& d = c.document;
  EXPECT_EQ(d["method"].as<std::string>(), "efg");
  EXPECT_EQ(d["title"].as<std::string>(), "small bar");
  EXPECT_EQ(d["materials"][0]["name"].as<std::string>(), "Steel");
  EXPECT_DOUBLE_EQ(d["materials"][0]["E"].as<double>(), 200.0);
  EXPECT_EQ(d["geometry"]["type"].as<std::string>(), "box");
  EXPECT_DOUBLE_EQ(d["geometry"]["max"][0].as<double>(), 2.0);
  // a uniform grid: node counts
  EXPECT_EQ(d["discretization"]["nodes"][0].as<int>(), 3);
  EXPECT_EQ(d["discretization"]["nodes"][1].as<int>(), 2);
  // x = 0 clamped: one plane per component
  ASSERT_EQ(d["boundary"].size(), 3u);
  EXPECT_EQ(d["boundary"][0]["select"]["where"].as<std::string>().rfind("abs(x - 0) <", 0), 0u);
  EXPECT_EQ(d["loads"][0]["force"][2].as<double>(), -1.5);
  EXPECT_DOUBLE_EQ(d["loads"][0]["select"]["nearest"][0].as<double>(), 2.0);
  const YAML::Node efg = d["efg"];
  EXPECT_EQ(efg["formulation"].as<std::string>(), "galerkin");
  EXPECT_EQ(efg["basis"].as<std::string>(), "linear");
  EXPECT_EQ(efg["weight"].as<std::string>(), "gauss");
  EXPECT_DOUBLE_EQ(efg["gauss_beta"].as<double>(), 2.5);
  EXPECT_DOUBLE_EQ(efg["support"]["radius"][2].as<double>(), 1.5);
  EXPECT_EQ(efg["integration"]["cells"][0].as<int>(), 2);
  EXPECT_EQ(efg["integration"]["cells"][1].as<int>(), 1);
  EXPECT_EQ(efg["integration"]["gauss"][2].as<int>(), 3);
  EXPECT_EQ(efg["essential_bc"].as<std::string>(), "penalty_nodes");
  EXPECT_DOUBLE_EQ(efg["penalty"].as<double>(), 1.0e7);
  EXPECT_EQ(d["probes"][0]["name"].as<std::string>(), "u3_z");
  // positions of generated keys point into the deck
  EXPECT_EQ(c.positions.at("materials.0.E").first, 10);
}

TEST(io_omll_deck, least_square_selects_weighted_least_squares) {
  const OmllCase c = parse_omll_deck(small_deck("LeastSquare"), "small.omll");
  EXPECT_EQ(c.document["efg"]["formulation"].as<std::string>(), "weighted_least_squares");
  EXPECT_DOUBLE_EQ(c.document["efg"]["weighted_least_squares"]["traction_weight"].as<double>(), 1.0e7);
  EXPECT_FALSE(c.document["efg"]["essential_bc"].IsDefined());
}

TEST(io_omll_deck, irregular_nodes_become_an_inline_list) {
  std::string text = small_deck();
  const auto at = text.find("\n2 1.0 0.0 0.0\n");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 15, "\n2 1.2 0.0 0.0\n");
  // the cells are no longer a tensor grid of corner levels either: drop them
  const auto cells = text.find("EFGDATA");
  text.erase(cells, text.find("ENDDATA") - cells);
  const OmllCase c = parse_omll_deck(text, "small.omll");
  const YAML::Node nodes = c.document["discretization"]["nodes"];
  ASSERT_TRUE(nodes.IsMap());
  ASSERT_EQ(nodes["coordinates"].size(), 12u);
  EXPECT_DOUBLE_EQ(nodes["coordinates"][1][0].as<double>(), 1.2);
}

TEST(io_omll_deck, problems_carry_the_deck_line) {
  std::string text = small_deck();
  text.replace(text.find("NUMNP 12"), 8, "NUMNP 13");
  auto problems = problems_of(text);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].line, 4);
  EXPECT_EQ(problems[0].key_path, "NUMNP");

  problems = problems_of(small_deck("EFGM", "FROBNICATE 3\n"));
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].key_path, "FROBNICATE");
  EXPECT_NE(problems[0].expected.find("batch"), std::string::npos);  // an unknown command inside BATCH

  text = small_deck();
  text.replace(text.find("3 Steel 0 0 0 0 0 1"), 1, "99");
  problems = problems_of(text);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].found.find("99"), std::string::npos);

  text = small_deck();
  text.erase(text.find("STOP"));
  problems = problems_of(text);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].key_path, "STOP");

  text = small_deck();
  text.replace(text.find("INFLENCEDOMAIN Fix 1.5 1.5 1.5"), 30, "INFLENCEDOMAIN Fix 1.5 -1 1.5");
  problems = problems_of(text);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_GT(problems[0].column, 20);

  text = small_deck();
  text.replace(text.find("Steel 2 3 6 5 8 9 12 11"), 23, "Steel 2 2 6 5 8 9 12 11");
  problems = problems_of(text);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].key_path, "CELL");
  EXPECT_EQ(problems[0].line, 43);  // the second cell row
}

TEST(io_omll_deck, cells_that_are_no_tensor_grid_are_approximated_and_noted) {
  std::string text = small_deck();
  text.replace(text.find("Steel 2 3 6 5 8 9 12 11"), 23, "Steel 1 3 6 5 8 9 12 11");
  const OmllCase c = parse_omll_deck(text, "small.omll");
  ASSERT_EQ(c.notes.size(), 2u);  // the grid note and the approximation
  EXPECT_NE(c.notes[1].find("approximation"), std::string::npos);
  EXPECT_TRUE(c.document["efg"]["integration"]["cells"].IsSequence());
  // the regular deck has no approximation note
  EXPECT_EQ(parse_omll_deck(small_deck(), "small.omll").notes.size(), 1u);
}

TEST(io_omll_deck, recognises_the_extension) {
  EXPECT_TRUE(is_omll_deck("a/b/plate.omll"));
  EXPECT_TRUE(is_omll_deck("PLATE.OMLL"));
  EXPECT_FALSE(is_omll_deck("plate.yaml"));
}

double probe_of(const std::filesystem::path& summary, const std::string& name) {
  std::ifstream in(summary);
  nlohmann::json j;
  in >> j;
  return j.at("probes").at(name).get<double>();
}

TEST(io_omll_deck, convert_then_run_matches_running_the_deck) {
  const std::filesystem::path deck = std::filesystem::path(LAMINA_SOURCE_DIR) / "examples" / "omll_clamped_plate.omll";
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("lamina_omll_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string lamina = LAMINA_BINARY;
  const std::string yaml = (dir / "plate.yaml").string();
  ASSERT_EQ(std::system((lamina + " convert " + deck.string() + " > " + yaml).c_str()), 0);
  ASSERT_EQ(std::system((lamina + " run " + deck.string() + " --quiet --threads 1 -o " + (dir / "deck").string()).c_str()), 0);
  ASSERT_EQ(std::system((lamina + " run " + yaml + " --quiet --threads 1 -o " + (dir / "yaml").string()).c_str()), 0);
  const double from_deck = probe_of(dir / "deck" / "summary.json", "u242_z");
  const double from_yaml = probe_of(dir / "yaml" / "summary.json", "u242_z");
  EXPECT_EQ(from_deck, from_yaml);
  // the plate deflects downwards, near the seed's -1.02343 (point load, 11 x 11 x 3 nodes)
  EXPECT_LT(from_deck, -0.9);
  EXPECT_GT(from_deck, -1.2);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace lamina::io
