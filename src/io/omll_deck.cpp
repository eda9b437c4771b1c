#include "io/omll_deck.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "core/error.hpp"
#include "io/omll_deck_parser.hpp"

namespace lamina::io {

using omll_detail::DeckParser;
using omll_detail::upper;

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
