// CaseReader (io/case_reader.hpp): no follow-on errors after an unknown method, the sections of a
// method (and its own discretization keys) read by its own reader, the node-count limit, and cases built in code (OMLL decks).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "core/error.hpp"
#include "io/case_reader.hpp"
#include "material/material_registry.hpp"

namespace lamina::io {
namespace {

std::vector<MethodKeys> methods() {
  return {MethodKeys{"mls_fit", {"nodes", "jitter"}, false},
          MethodKeys{"pd", {"spacing", "horizon", "horizon_factor"}, true, {"imperfection"}, {"horizon", "horizon_factor"}}};
}

std::vector<Diagnostic> read_problems(const std::string& text, const std::vector<std::string>& overrides = {}) {
  // one file per test and process: ctest runs the tests of this file in parallel
  const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
  const auto path = (std::filesystem::temp_directory_path() /
                     ("lamina_case_reader_" + std::string(test ? test->name() : "test") + "_" +
                      std::to_string(::getpid()) + ".yaml"))
                        .string();
  std::ofstream(path) << text;
  try {
    CaseReader reader(path, overrides, methods());
    (void)reader.read();
    reader.finish();
  } catch (const InputError& e) {
    return e.diagnostics();
  }
  return {};
}

const char* kPdCase =
    "method: pd\n"
    "materials: [{E: 1.0e4, nu: 0.25, density: 1}]\n"
    "geometry: {type: box, min: [0, 0, 0], max: [10, 10, 1]}\n"
    "discretization: {spacing: [0.5, 0.5, 0.5], horizon_factor: 3.015}\n"
    "pd: {influence: one}\n"
    "imperfection: {shape: sine}\n";

TEST(io_case_reader, a_method_section_and_its_other_sections_are_left_to_the_method) {
  EXPECT_TRUE(read_problems(kPdCase).empty());
}

TEST(io_case_reader, an_unknown_method_has_no_follow_on_errors) {
  std::string text = kPdCase;
  text.replace(0, 10, "method: fem");
  const auto problems = read_problems(text);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].key_path, "method");
  EXPECT_EQ(problems[0].line, 1);
}

TEST(io_case_reader, total_node_count_is_limited) {
  const auto problems = read_problems(
      "method: mls_fit\ngeometry: {type: box, min: [0, 0, 0], max: [1, 1, 1]}\n"
      "discretization: {nodes: [3000, 3000, 3000]}\nmls_fit: {field: x}\n");
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].key_path, "discretization.nodes");
  EXPECT_NE(problems[0].found.find("27000000000"), std::string::npos);
}

TEST(io_case_reader, pd_spacing_giving_too_many_nodes_is_rejected) {
  std::string text = kPdCase;
  text.replace(text.find("[0.5, 0.5, 0.5]"), 15, "[0.001, 0.001, 0.01]");
  const auto problems = read_problems(text);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].key_path, "discretization.spacing");
}

TEST(io_case_reader, a_case_built_in_code_reports_recorded_positions) {
  YAML::Node doc = YAML::Load(kPdCase);
  // a document built in code has no marks (the geometry is copied from a loaded one)
  YAML::Node built(YAML::NodeType::Map);
  built["method"] = "pd";
  built["materials"].push_back(YAML::Node(YAML::NodeType::Map));
  built["materials"][0]["E"] = "-5";
  built["materials"][0]["nu"] = "0.25";
  built["geometry"] = YAML::Clone(doc["geometry"]);
  std::map<std::string, std::pair<int, int>> positions{{"materials.0", {12, 1}}, {"materials.0.E", {12, 20}}};
  CaseReader reader("deck.omll", built, positions, {}, methods());
  (void)reader.read();
  try {
    reader.finish();
    FAIL() << "accepted E = -5";
  } catch (const InputError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    EXPECT_EQ(e.diagnostics()[0].file, "deck.omll");
    EXPECT_EQ(e.diagnostics()[0].line, 12);
    EXPECT_EQ(e.diagnostics()[0].column, 20);
  }
}

// Every registered material model is accepted by name and gets each of its constants: the given value,
// or the registry's default when the entry leaves it out.
TEST(io_case_reader, material_constants_come_from_the_registry) {
  for (const auto& info : material::material_models()) {
    std::string entry = "{model: " + info.name + ", E: 1.0e4, nu: 0.25, density: 1";
    for (const auto& k : info.constants)
      if (!k.fallback) entry += ", " + k.key + ": 7.5";  // a required constant, within every range used
    entry += "}";
    std::string text = kPdCase;
    text.replace(text.find("[{E: 1.0e4, nu: 0.25, density: 1}]"), 34, "[" + entry + "]");
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    const auto path = (std::filesystem::temp_directory_path() /
                       ("lamina_case_reader_" + std::string(test->name()) + "_" + std::to_string(::getpid()) + ".yaml"))
                          .string();
    std::ofstream(path) << text;
    CaseReader reader(path, {}, methods());
    const Case c = reader.read();
    reader.finish();
    ASSERT_EQ(c.materials.size(), 1u);
    const auto& spec = c.materials[0].spec;
    EXPECT_EQ(spec.model, info.model) << info.name;
    EXPECT_EQ(spec.constants.size(), info.constants.size()) << info.name;
    for (const auto& k : info.constants) EXPECT_EQ(spec.constant(k.key), k.fallback.value_or(7.5)) << info.name << " " << k.key;
  }
  const auto* j2 = material::find_material_model("j2_plasticity");
  ASSERT_NE(j2, nullptr);
  EXPECT_EQ(material::find_material_model("no_such_model"), nullptr);
}

}  // namespace
}  // namespace lamina::io
