// Throughput of the Galerkin EFG volume assembly on the clamped plate R1a refined to 41 x 41 x 5 nodes
// (box [0, 10] x [0, 10] x [0, 1], 40 x 40 x 4 background cells, 2 x 2 x 2 Gauss points: 51,200
// points): 3D quadratic basis, quartic spline, the seed's recommended box support kappa = 2.01 (64
// neighbours per Gauss point) and the validation case's kappa = 3.
//
// Timed, as in the analysis's stage_gauss_points_per_second: pass 1 (neighbour lists per cell) plus
// pass 2 (MLS shape functions with first derivatives at every Gauss point, cell products, adding into
// the sparse matrix, which is allocated and zeroed inside the timing). The sparsity pattern is built
// once, outside. Best of 5 runs per thread count. Ends with "BENCH <name> <value> <unit>" lines (see
// bench/README.md).
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "efg/background_quadrature.hpp"
#include "efg/galerkin_assembly.hpp"
#include "geometry/body_maps.hpp"
#include "solve/block_pattern.hpp"

namespace {

using namespace lamina;

struct Result {
  Real seconds = std::numeric_limits<Real>::infinity();
  Real neighbours = 0;  // mean per Gauss point
  Real checksum = 0;
};

Result run(Real kappa, int threads, int repeats) {
  omp_set_num_threads(threads);
  constexpr int nx = 41, ny = 41, nz = 5;
  geometry::GeometrySpec box;
  box.type = geometry::GeometryType::box;
  box.min = Vec3::Zero();
  box.max = Vec3(10, 10, 1);
  PointMatrix nodes(3, nx * ny * nz);
  Index column = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) nodes.col(column++) = Vec3(10.0 * i / (nx - 1), 10.0 * j / (ny - 1), 1.0 * k / (nz - 1));
  const Eigen::Matrix3Xd spacing = Eigen::Matrix3Xd::Constant(3, nodes.cols(), 0.25);
  mls::MlsOptions options;  // quadratic basis, quartic spline, box support, kappa mode
  options.kappa = kappa;
  const mls::MlsShapeFunctions shapes(nodes, options, spacing);
  const efg::BackgroundCells cells = efg::make_background_cells(geometry::make_volume_map(box), {nx - 1, ny - 1, nz - 1});
  const efg::VolumeQuadrature quadrature = efg::volume_quadrature(cells, {2, 2, 2});
  const std::vector<int> material_of_point(static_cast<std::size_t>(quadrature.size()), 0);
  const std::vector<material::LinearElastic> materials{{1e4, 0.3}};

  std::vector<IndexList> groups;
  const std::vector<IndexList> cell_nodes = efg::cell_neighbours(shapes, quadrature, nullptr, &groups);
  const solve::BlockPattern pattern(shapes.node_count(), 3, groups, true);
  Result result;
  for (const auto& g : groups) result.neighbours += static_cast<Real>(g.size());
  result.neighbours /= static_cast<Real>(std::max<std::size_t>(groups.size(), 1));
  groups.clear();

  efg::VolumeAssembly input;
  input.shapes = &shapes;
  input.quadrature = &quadrature;
  input.material_of_point = &material_of_point;
  input.materials = &materials;
  for (int r = 0; r < repeats; ++r) {
    const auto start = std::chrono::steady_clock::now();
    const std::vector<IndexList> timed_cell_nodes = efg::cell_neighbours(shapes, quadrature, nullptr);
    input.cell_nodes = &timed_cell_nodes;
    const auto t1 = std::chrono::steady_clock::now();
    solve::SparseMatrix K = pattern.zero_matrix();
    const auto t2 = std::chrono::steady_clock::now();
    Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * shapes.node_count());
    efg::assemble_volume(input, pattern, K.valuePtr(), f);
    const auto end = std::chrono::steady_clock::now();
    const Real seconds = std::chrono::duration<Real>(end - start).count();
    result.seconds = std::min(result.seconds, seconds);
    std::printf("  run %d: neighbours %.3f s, matrix allocation %.3f s, assembly %.3f s\n", r + 1,
                std::chrono::duration<Real>(t1 - start).count(), std::chrono::duration<Real>(t2 - t1).count(),
                std::chrono::duration<Real>(end - t2).count());
    result.checksum = K.coeffs().sum();
  }
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 5;
  if (argc > 1) repeats = std::max(1, std::stoi(argv[1]));
  const int available = omp_get_max_threads();
  std::vector<std::string> lines;
  for (const auto& [kappa, label] : {std::pair<Real, const char*>{2.01, "kappa2"}, {3.0, "kappa3"}}) {
    Real one_thread = 0;
    for (int threads : {1, 2}) {
      if (threads > available && threads > 1) continue;
      const Result r = run(kappa, threads, repeats);
      const Real points = 51200.0 / r.seconds;
      std::printf("box kappa %.2f, %d thread(s): %.3f s, %.0f Gauss points/s, %.1f neighbours per point (checksum %.9e)\n",
                  kappa, threads, r.seconds, points, r.neighbours, r.checksum);
      lines.push_back("BENCH efg_assembly_" + std::string(label) + "_" + std::to_string(threads) + "thread_points_per_second " +
                      std::to_string(static_cast<long long>(points)) + " points/s");
      if (threads == 1) one_thread = r.seconds;
      else if (one_thread > 0)
        lines.push_back("BENCH efg_assembly_" + std::string(label) + "_speedup_2threads " +
                        std::to_string(one_thread / r.seconds).substr(0, 4) + " ratio");
      if (threads == 2 && kappa < 2.5)
        lines.push_back("BENCH efg_assembly_kappa2_2thread_over_target " + std::to_string(points / 200000.0).substr(0, 4) +
                        " ratio");
    }
  }
  for (const auto& line : lines) std::puts(line.c_str());
  return 0;
}
