#pragma once
// Reader of OMLL macro-command decks (seed 004 section 2.2: the thesis's object-oriented meshless
// program): converts a deck into the equivalent lamina case document (method: efg). docs/omll.md.
#include <yaml-cpp/yaml.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace lamina::io {

/// A deck converted to a case: the document (as a YAML case file would load) and, for the
/// diagnostics of the case reader, the deck line and column of each key path it generated.
struct OmllCase {
  YAML::Node document;
  std::map<std::string, std::pair<int, int>> positions;
  std::vector<std::string> notes;  // approximations made in the conversion (printed by `lamina convert`)
};

/// Whether `path` names an OMLL deck (extension .omll, any case).
bool is_omll_deck(const std::string& path);

/// Read and convert a deck file. Problems throw InputError, one Diagnostic per problem with the
/// deck's file:line:column, the command and what was expected.
OmllCase read_omll_deck(const std::string& path);

/// The same for deck text; `file` names it in the diagnostics.
OmllCase parse_omll_deck(const std::string& text, const std::string& file);

/// The converted case as YAML text (what `lamina convert` prints): a comment header naming the
/// deck and the conversion's notes, then the document.
std::string omll_case_yaml(const OmllCase& converted, const std::string& deck_path);

}  // namespace lamina::io
