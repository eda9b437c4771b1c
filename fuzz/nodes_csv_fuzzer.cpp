// libFuzzer target for the node-coordinate CSV reader (`discretization.nodes: {file: ...}` and
// mpfem's `discretization.particles: {file: ...}`, both read_nodes_csv in src/app/model.cpp; see
// fuzz/README.md).
//
// A fixed mls_fit case naming scratch/nodes.csv is read once; each input becomes that file, and
// the harness does what `lamina check` does - build the point model (the file is read, the
// nodes get their volumes, selections are resolved) and create the analysis - and, for at most
// kMaxRunNodes nodes, also runs the mls_fit analysis and its built-in probes, so that the rest of
// lamina meets the coordinates the reader lets through (neighbour search, spacing, MLS fit).
// Expected outcome: success, lamina::InputError, or (for the run) lamina::AnalysisError;
// anything else aborts (fuzz_support.hpp).
#include <cstdint>
#include <string>
#include <vector>

#include "app/model.hpp"
#include "app/run_command.hpp"
#include "fuzz_support.hpp"

namespace {

constexpr const char* kTarget = "nodes_csv_fuzzer";
constexpr lamina::Index kMaxRunNodes = 64;

constexpr const char* kCase = R"(method: mls_fit
geometry: {type: box, min: [0, 0, 0], max: [1, 1, 1]}
discretization:
  nodes: {file: nodes.csv}
mls_fit:
  field: "x*y + z"
  basis: linear
  weight: quartic_spline
  support: {shape: box, kappa: 2.0}
)";

class NullSink : public lamina::OutputSink {
 public:
  void output_point(lamina::Index, lamina::Real, lamina::Real) override {}
  void progress(lamina::Real, const std::string&) override {}
};

const lamina::app::PreparedCase& prepared() {
  static const lamina::app::PreparedCase p = [] {
    lamina::fuzz::write_scratch("nodes.csv", "x,y,z\n0,0,0\n1,1,1\n");
    try {
      return lamina::app::prepare_case(lamina::fuzz::write_scratch("case.yaml", kCase), {});
    } catch (const std::exception& e) {
      lamina::fuzz::finding(kTarget, std::string("the harness's case is refused: ") + e.what());
    }
  }();
  return p;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  (void)prepared();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const lamina::app::PreparedCase& p = prepared();
  lamina::fuzz::write_scratch("nodes.csv", data, size);
  lamina::fuzz::expect_input_errors(
      kTarget,
      [&] {
        const lamina::app::Model model = lamina::app::build_point_model(p.case_data);
        auto analysis = p.method->create(p.case_data, model, *p.options);
        if (model.cloud.size() > kMaxRunNodes) return;
        NullSink sink;
        analysis->run(sink);
        (void)analysis->builtin_probes();
      },
      /*analysis_errors_ok=*/true);
  return 0;
}
