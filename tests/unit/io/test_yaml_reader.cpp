// The validating YAML layer (io/yaml_reader.hpp): --set errors from the command line, unclosed
// quotes, key-path positions, diagnostics in line order.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "io/yaml_reader.hpp"

namespace lamina::io {
namespace {

TEST(io_yaml_reader, set_below_a_scalar_is_a_command_line_error) {
  YAML::Node root = YAML::Load("title: plain\nmaterials: [{E: 1}]\n");
  DiagnosticSink sink("case.yaml");
  apply_override(root, "title.x=1", sink);
  ASSERT_EQ(sink.diagnostics().size(), 1u);
  EXPECT_EQ(sink.diagnostics()[0].file, "--set title.x=1");
  EXPECT_NE(sink.diagnostics()[0].expected.find("a mapping"), std::string::npos);
  EXPECT_EQ(root["title"].as<std::string>(), "plain");  // untouched

  DiagnosticSink ok("case.yaml");
  apply_override(root, "materials.0.E=2", ok);
  EXPECT_TRUE(ok.empty());
  EXPECT_EQ(root["materials"][0]["E"].as<int>(), 2);

  DiagnosticSink bad_index("case.yaml");
  apply_override(root, "materials.3.E=2", bad_index);
  ASSERT_EQ(bad_index.diagnostics().size(), 1u);
  EXPECT_EQ(bad_index.diagnostics()[0].file, "--set materials.3.E=2");
}

std::string write(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / name;
  std::ofstream(path) << text;
  return path.string();
}

TEST(io_yaml_reader, unclosed_quote_is_a_syntax_error_at_its_line) {
  const std::string path = write("lamina_unclosed.yaml", "a: 1\nb: 'it''s fine'\nc: it's plain\nd: \"open\ne: 2\n");
  DiagnosticSink sink(path);
  try {
    (void)load_yaml_file(path, sink);
    FAIL() << "accepted an unclosed quote";
  } catch (const InputError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    EXPECT_EQ(e.diagnostics()[0].line, 4);
    EXPECT_EQ(e.diagnostics()[0].key_path, "<yaml syntax>");
  }
  const std::string fine = write("lamina_closed.yaml",
                                 "a: \"x # y\"  # it's a comment\nb: |\n  \"quoted in a block\n  it's\nc: ['a', \"b\"]\n");
  DiagnosticSink sink2(fine);
  EXPECT_NO_THROW((void)load_yaml_file(fine, sink2));
  std::filesystem::remove(path);
  std::filesystem::remove(fine);
}

TEST(io_yaml_reader, position_of_follows_the_key_path) {
  const YAML::Node root = YAML::Load("geometry:\n  type: box\n  thickness: 2\nlist:\n  - a\n  - {b: 1}\n");
  auto p = position_of(root, "geometry.thickness");
  ASSERT_TRUE(p);
  EXPECT_EQ(p->first, 3);
  EXPECT_EQ(p->second, 14);
  p = position_of(root, "list.1.b");
  ASSERT_TRUE(p);
  EXPECT_EQ(p->first, 6);
  p = position_of(root, "geometry.missing");  // deepest existing ancestor
  ASSERT_TRUE(p);
  EXPECT_EQ(p->first, 2);
}

TEST(io_yaml_reader, diagnostics_are_sorted_by_line) {
  std::vector<Diagnostic> d{{"f", 9, 1, "c", "", ""}, {"--set x=1", 0, 0, "x", "", ""}, {"f", 3, 5, "a", "", ""},
                            {"f", 3, 2, "b", "", ""}};
  sort_by_position(d);
  EXPECT_EQ(d[0].key_path, "b");
  EXPECT_EQ(d[1].key_path, "a");
  EXPECT_EQ(d[2].key_path, "c");
  EXPECT_EQ(d[3].key_path, "x");
}

}  // namespace
}  // namespace lamina::io
