// libFuzzer target for the OMLL macro-deck reader (src/io/omll_deck.*; see fuzz/README.md).
//
// Each input is a deck. It is written to scratch/deck.omll and read as the program reads it:
//   - `lamina convert`: read_omll_deck + omll_case_yaml (the converted case as YAML text);
//   - `lamina check`/`run`: prepare_case(deck.omll) (conversion, then the case reader on the
//     converted document with the deck's line numbers) and, for at most 4000 nodes, the point
//     model (selections of the converted boundary and loads resolved).
// When the deck is accepted, the YAML that `lamina convert` prints must be accepted as a case
// too (docs/omll.md: running the converted case gives the deck's results).
// Expected outcome: success or lamina::InputError; anything else aborts (fuzz_support.hpp).
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>

#include "app/model.hpp"
#include "app/run_command.hpp"
#include "fuzz_support.hpp"
#include "io/omll_deck.hpp"

namespace {

constexpr const char* kTarget = "omll_deck_fuzzer";
constexpr long long kMaxModelNodes = 4000;

bool small_model(const lamina::io::Case& c) {
  const auto& d = c.discretization;
  if (d.node_coordinates) return d.node_coordinates->size() <= static_cast<std::size_t>(kMaxModelNodes);
  if (!d.nodes) return false;
  long long total = 1;
  for (int n : *d.nodes) total *= n;
  return total <= kMaxModelNodes;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string deck = lamina::fuzz::write_scratch("deck.omll", data, size);
  std::string converted;
  lamina::fuzz::expect_input_errors(kTarget, [&] {
    converted = lamina::io::omll_case_yaml(lamina::io::read_omll_deck(deck), deck);
  });
  bool accepted = false;
  lamina::fuzz::expect_input_errors(kTarget, [&] {
    lamina::app::PreparedCase prepared = lamina::app::prepare_case(deck, {});
    accepted = true;
    if (small_model(prepared.case_data)) (void)lamina::app::build_point_model(prepared.case_data);
  });
  if (accepted) {
    if (converted.empty()) lamina::fuzz::finding(kTarget, "the deck is accepted by prepare_case but not converted");
    const std::string yaml = lamina::fuzz::write_scratch("converted.yaml", converted);
    try {
      (void)lamina::app::prepare_case(yaml, {});
    } catch (const std::exception& e) {
      lamina::fuzz::finding(kTarget, std::string("the accepted deck's converted YAML is refused: ") + e.what());
    }
  }
  return 0;
}
