// libFuzzer target for the pd imperfection-shape CSV reader (`imperfection: {file: ...}`,
// read_imperfection_file in src/app/pd_method.cpp; see fuzz/README.md).
//
// A fixed pd case (a 4 x 4 x 2 lattice; a short horizon and no surface correction, whose
// calibration would take most of each execution) naming scratch/imperfection.csv is read and its point
// model built once; each input becomes that file and the harness creates the analysis, as
// `lamina check` and `lamina run` do: the method reads the file (x, y, z, ux, uy, uz rows, the
// nearest row onto each node), scales the shape to the amplitude and builds the peridynamic body
// on the imperfect positions.
// Expected outcome: success or lamina::InputError; anything else aborts (fuzz_support.hpp).
#include <cstdint>
#include <string>

#include "app/model.hpp"
#include "app/run_command.hpp"
#include "fuzz_support.hpp"

namespace {

constexpr const char* kTarget = "imperfection_csv_fuzzer";

constexpr const char* kCase = R"(method: pd
materials:
  - {name: plate, E: 1.0e4, nu: 0.25, density: 1.0}
geometry: {type: box, min: [0, 0, 0], max: [4, 4, 1]}
discretization: {spacing: [1, 1, 0.5], horizon_factor: 1.6}
boundary:
  - {select: {where: "x < 0.6"}, fix: [x, y, z]}
loads:
  - {select: {where: "x > 3.4"}, force: [1, 0, 0]}
imperfection: {amplitude: 0.1, file: imperfection.csv}
pd: {analysis: quasi_static, surface_correction: none}
)";

struct Fixture {
  lamina::app::PreparedCase prepared;
  lamina::app::Model model;
};

const Fixture& fixture() {
  static const Fixture f = [] {
    lamina::fuzz::write_scratch("imperfection.csv", "x,y,z,ux,uy,uz\n0,0,0,0,0,1\n");
    try {
      Fixture out;
      out.prepared = lamina::app::prepare_case(lamina::fuzz::write_scratch("case.yaml", kCase), {});
      out.model = lamina::app::build_point_model(out.prepared.case_data);
      return out;
    } catch (const std::exception& e) {
      lamina::fuzz::finding(kTarget, std::string("the harness's case is refused: ") + e.what());
    }
  }();
  return f;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  (void)fixture();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const Fixture& f = fixture();
  lamina::fuzz::write_scratch("imperfection.csv", data, size);
  lamina::fuzz::expect_input_errors(kTarget, [&] {
    (void)f.prepared.method->create(f.prepared.case_data, f.model, *f.prepared.options);
  });
  return 0;
}
