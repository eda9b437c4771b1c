// Throughput of MLS shape functions with first derivatives: 3D quadratic basis (m = 10), quartic
// spline, box supports with kappa = 1.7 (radius (kappa + delta) h = 1.8 h) on a regular 40^3 grid
// (about 46 neighbours per point).
// Evaluation points: 8 random points in each unit background cell, cells visited in order (the
// access pattern of an EFG assembly), and the same points in random order. Ends with "BENCH <name> <value> <unit>" lines
// (see bench/README.md).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "mls/mls_shape_functions.hpp"

namespace {

using lamina::Index;
using lamina::PointMatrix;
using lamina::Real;
using lamina::Vec3;
using namespace lamina::mls;

constexpr int grid_nodes_per_axis = 40;  // 64,000 nodes, spacing 1
constexpr int cells_per_axis = 17;       // background cells [2, 19]^3: 4,913 cells x 8 points

const MlsShapeFunctions& shape_functions() {
  static const MlsShapeFunctions instance = [] {
    const int n = grid_nodes_per_axis;
    PointMatrix nodes(3, n * n * n);
    Index column = 0;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) nodes.col(column++) = Vec3(i, j, k);
    MlsOptions options;  // quadratic basis, quartic spline, box support, kappa mode
    options.kappa = 1.7;
    return MlsShapeFunctions(std::move(nodes), options);
  }();
  return instance;
}

/// 8 uniformly random points in each unit background cell, cell after cell. (Gauss points at fixed
/// offsets would see either 27 or 64 neighbours with this support, random points 46 on average.)
const PointMatrix& cell_ordered_points() {
  static const PointMatrix instance = [] {
    std::mt19937 generator(7);
    std::uniform_real_distribution<Real> uniform(0.0, 1.0);
    PointMatrix p(3, 8 * cells_per_axis * cells_per_axis * cells_per_axis);
    Index column = 0;
    for (int k = 0; k < cells_per_axis; ++k)
      for (int j = 0; j < cells_per_axis; ++j)
        for (int i = 0; i < cells_per_axis; ++i)
          for (int g = 0; g < 8; ++g)
            p.col(column++) = Vec3(2.0 + i + uniform(generator), 2.0 + j + uniform(generator), 2.0 + k + uniform(generator));
    return p;
  }();
  return instance;
}

/// The same points shuffled (no spatial locality between successive points).
const PointMatrix& random_order_points() {
  static const PointMatrix instance = [] {
    const PointMatrix& ordered = cell_ordered_points();
    std::vector<Index> permutation(static_cast<std::size_t>(ordered.cols()));
    for (std::size_t i = 0; i < permutation.size(); ++i) permutation[i] = static_cast<Index>(i);
    std::shuffle(permutation.begin(), permutation.end(), std::mt19937(42));
    PointMatrix p(3, ordered.cols());
    for (Index i = 0; i < ordered.cols(); ++i) p.col(i) = ordered.col(permutation[static_cast<std::size_t>(i)]);
    return p;
  }();
  return instance;
}

double process_cpu_seconds() {
  timespec time{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &time);
  return static_cast<double>(time.tv_sec) + 1e-9 * static_cast<double>(time.tv_nsec);
}

/// Evaluates every point (first derivatives) on `threads` threads, one reused output per thread.
/// Returns the elapsed wall-clock seconds; adds the process CPU seconds to *cpu_seconds if given.
double run_points(const PointMatrix& p, int threads, double* cpu_seconds = nullptr) {
  const MlsShapeFunctions& mls = shape_functions();
  double checksum = 0.0;
  const double cpu_start = process_cpu_seconds();
  const auto start = std::chrono::steady_clock::now();
#pragma omp parallel num_threads(threads) reduction(+ : checksum)
  {
    ShapeFunctionValues values;
#pragma omp for schedule(static, 512)
    for (Index i = 0; i < p.cols(); ++i) {
      mls.evaluate(p.col(i), 1, values);
      checksum += values.dphi(0, 0);
    }
  }
  const auto stop = std::chrono::steady_clock::now();
  if (cpu_seconds) *cpu_seconds = process_cpu_seconds() - cpu_start;
  benchmark::DoNotOptimize(checksum);
  return std::chrono::duration<double>(stop - start).count();
}

void evaluate_loop(benchmark::State& state, const PointMatrix& p, int order) {
  const MlsShapeFunctions& mls = shape_functions();
  ShapeFunctionValues values;
  Index i = 0;
  for (auto _ : state) {
    mls.evaluate(p.col(i), order, values);
    benchmark::DoNotOptimize(values.phi.data());
    i = (i + 1) % p.cols();
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_FirstDerivativesCellOrder(benchmark::State& state) { evaluate_loop(state, cell_ordered_points(), 1); }
BENCHMARK(BM_FirstDerivativesCellOrder);
void BM_FirstDerivativesRandomOrder(benchmark::State& state) { evaluate_loop(state, random_order_points(), 1); }
BENCHMARK(BM_FirstDerivativesRandomOrder);
void BM_ValuesCellOrder(benchmark::State& state) { evaluate_loop(state, cell_ordered_points(), 0); }
BENCHMARK(BM_ValuesCellOrder);
void BM_SecondDerivativesCellOrder(benchmark::State& state) { evaluate_loop(state, cell_ordered_points(), 2); }
BENCHMARK(BM_SecondDerivativesCellOrder);

void BM_EvaluateAll(benchmark::State& state) {
  const MlsShapeFunctions& mls = shape_functions();
  const PointMatrix batch = cell_ordered_points().leftCols(8000);
  omp_set_num_threads(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    auto results = mls.evaluate_all(batch, 1);
    benchmark::DoNotOptimize(results.data());
  }
  state.SetItemsProcessed(state.iterations() * batch.cols());
}
BENCHMARK(BM_EvaluateAll)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();

  // Own timing loop (wall clock): best of 7 runs over all evaluation points.
  const MlsShapeFunctions& mls = shape_functions();
  const PointMatrix& ordered = cell_ordered_points();
  double neighbours = 0.0;
  ShapeFunctionValues values;
  Index sampled = 0;
  for (Index i = 0; i < ordered.cols(); i += 97, ++sampled) {
    mls.evaluate(ordered.col(i), 1, values);
    neighbours += static_cast<double>(values.neighbours.size());
  }
  neighbours /= static_cast<double>(sampled);
  run_points(ordered, 1);  // warm-up (thread-local scratch, caches)
  run_points(ordered, 2);
  double best_one = 1e30, best_two = 1e30, best_random = 1e30, best_cpu = 1e30, best_cpu_two = 1e30;
  for (int repeat = 0; repeat < 7; ++repeat) {
    double cpu = 0.0;
    best_one = std::min(best_one, run_points(ordered, 1, &cpu));
    best_cpu = std::min(best_cpu, cpu);
    double cpu_two = 0.0;
    const double two = run_points(ordered, 2, &cpu_two);
    if (two < best_two) {
      best_two = two;
      best_cpu_two = cpu_two;
    }
    best_random = std::min(best_random, run_points(random_order_points(), 1));
  }
  const double count = static_cast<double>(ordered.cols());
  std::printf("BENCH mls_points_per_second_1thread %.0f points/s\n", count / best_one);
  std::printf("BENCH mls_points_per_second_2threads %.0f points/s\n", count / best_two);
  std::printf("BENCH mls_speedup_2threads %.2f ratio\n", best_one / best_two);
  std::printf("BENCH mls_points_per_second_1thread_random_order %.0f points/s\n", count / best_random);
  // CPU time of the 1-thread run: the throughput without the time slices other processes take.
  std::printf("BENCH mls_points_per_cpu_second_1thread %.0f points/s\n", count / best_cpu);
  // CPU seconds of the 1-thread run / CPU seconds of the (best) 2-thread run: 1.0 = no parallel
  // overhead; the wall-clock speed-up can only reach 2 x this when both cores are free.
  std::printf("BENCH mls_cpu_efficiency_2threads %.2f ratio\n", best_cpu / best_cpu_two);
  std::printf("BENCH mls_mean_neighbours %.1f nodes\n", neighbours);
  return 0;
}
