#include "efg/mls_fit_analysis.hpp"

#include <chrono>
#include <cmath>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "geometry/expression.hpp"

namespace lamina::efg {

namespace {

// 4th-order central difference weights for the first derivative at offsets -2..2 (times 1/h).
constexpr Real kFirst[5] = {1.0 / 12.0, -8.0 / 12.0, 0.0, 8.0 / 12.0, -1.0 / 12.0};
// ... and for the second derivative (times 1/h^2).
constexpr Real kSecond[5] = {-1.0 / 12.0, 16.0 / 12.0, -30.0 / 12.0, 16.0 / 12.0, -1.0 / 12.0};

}  // namespace

FieldDerivatives differentiate_expression(const std::string& text, const Vec3& x, Real h) {
  geometry::Expression f(text);
  FieldDerivatives out;
  out.value = f.evaluate(x);
  for (int d = 0; d < 3; ++d) {
    Real first = 0, second = 0;
    for (int k = 0; k < 5; ++k) {
      Vec3 p = x;
      p[d] += (k - 2) * h;
      const Real v = (k == 2) ? out.value : f.evaluate(p);
      first += kFirst[k] * v;
      second += kSecond[k] * v;
    }
    out.gradient[d] = first / h;
    out.hessian[d] = second / (h * h);
  }
  const int pairs[3][2] = {{0, 1}, {1, 2}, {2, 0}};  // xy yz zx
  for (int q = 0; q < 3; ++q) {
    const int a = pairs[q][0], b = pairs[q][1];
    Real mixed = 0;
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j) {
        if (kFirst[i] == 0.0 || kFirst[j] == 0.0) continue;
        Vec3 p = x;
        p[a] += (i - 2) * h;
        p[b] += (j - 2) * h;
        mixed += kFirst[i] * kFirst[j] * f.evaluate(p);
      }
    out.hessian[3 + q] = mixed / (h * h);
  }
  return out;
}

MlsFitAnalysis::MlsFitAnalysis(PointCloud cloud, MlsFitOptions options, std::vector<Probe> probes)
    : cloud_(std::move(cloud)), options_(std::move(options)) {
  for (const auto& p : probes)
    if (p.field != "approximation")
      throw InputError("probes." + p.name, "field approximation (mls_fit evaluates only the fitted field)", p.field);
}

void MlsFitAnalysis::run(OutputSink& sink) {
  const auto start = std::chrono::steady_clock::now();
  const Index n = cloud_.size();
  const Vec3 extent = cloud_.positions.rowwise().maxCoeff() - cloud_.positions.rowwise().minCoeff();
  const Real h = options_.difference_step * std::max(extent.maxCoeff(), 1e-300);

  exact_.resize(n);
  exact_gradient_.resize(3, n);
  exact_hessian_.resize(6, n);
  for (Index i = 0; i < n; ++i) {
    const FieldDerivatives d = differentiate_expression(options_.field, cloud_.positions.col(i), h);
    exact_[i] = d.value;
    exact_gradient_.col(i) = d.gradient;
    exact_hessian_.col(i) = d.hessian;
  }
  nodal_values_ = exact_;
  timings_["field_s"] = seconds_since(start);
  sink.progress(0.1, "field evaluated");

  const auto setup_start = std::chrono::steady_clock::now();
  shape_functions_ = std::make_unique<mls::MlsShapeFunctions>(cloud_.positions, options_.mls,
                                                              cloud_.spacing.cols() == n ? cloud_.spacing : Eigen::Matrix3Xd());
  timings_["setup_s"] = seconds_since(setup_start);

  const auto solve_start = std::chrono::steady_clock::now();
  const auto values = shape_functions_->evaluate_all(cloud_.positions, 2);
  approximation_.resize(n);
  gradient_.resize(3, n);
  hessian_.resize(6, n);
  for (Index i = 0; i < n; ++i) {
    const auto& v = values[static_cast<std::size_t>(i)];
    Real u = 0;
    Vec3 g = Vec3::Zero();
    Eigen::Matrix<Real, 6, 1> hh = Eigen::Matrix<Real, 6, 1>::Zero();
    for (std::size_t k = 0; k < v.neighbours.size(); ++k) {
      const Real uj = nodal_values_[v.neighbours[k]];
      u += v.phi[static_cast<Index>(k)] * uj;
      g += v.dphi.col(static_cast<Index>(k)) * uj;
      hh += v.ddphi.col(static_cast<Index>(k)) * uj;
    }
    approximation_[i] = u;
    gradient_.col(i) = g;
    hessian_.col(i) = hh;
  }
  timings_["solve_s"] = seconds_since(solve_start);

  // seed 004 eqs (3-3)-(3-5), in percent
  auto relative = [](Real error_squared, Real norm_squared) {
    return norm_squared > 0 ? 100.0 * std::sqrt(error_squared / norm_squared) : 100.0 * std::sqrt(error_squared);
  };
  error_value_ = relative((approximation_ - exact_).squaredNorm(), exact_.squaredNorm());
  error_gradient_ = relative((gradient_ - exact_gradient_).squaredNorm(), exact_gradient_.squaredNorm());
  error_hessian_ = relative((hessian_ - exact_hessian_).squaredNorm(), exact_hessian_.squaredNorm());
  if (!std::isfinite(error_value_) || !std::isfinite(error_gradient_) || !std::isfinite(error_hessian_))
    throw AnalysisError("the MLS fit produced non-finite values");
  sink.progress(1.0, "fit done");
  sink.output_point(1, 1.0, 1.0);
}

std::map<std::string, Real> MlsFitAnalysis::builtin_probes() const {
  return {{"errU", error_value_}, {"errDU", error_gradient_}, {"errDDU", error_hessian_}};
}

Real MlsFitAnalysis::probe(const Probe& probe) const {
  if (!shape_functions_ || !probe.at) return 0.0;
  mls::ShapeFunctionValues v;
  shape_functions_->evaluate(*probe.at, 2, v);
  static const std::map<std::string, int> first{{"x", 0}, {"y", 1}, {"z", 2}};
  static const std::map<std::string, int> second{{"xx", 0}, {"yy", 1}, {"zz", 2}, {"xy", 3}, {"yz", 4}, {"zx", 5}};
  Real result = 0;
  for (std::size_t k = 0; k < v.neighbours.size(); ++k) {
    const Real uj = nodal_values_[v.neighbours[k]];
    const Index kk = static_cast<Index>(k);
    if (probe.component == "value") result += v.phi[kk] * uj;
    else if (first.count(probe.component)) result += v.dphi(first.at(probe.component), kk) * uj;
    else result += v.ddphi(second.at(probe.component), kk) * uj;
  }
  return result;
}

OutputFrame MlsFitAnalysis::frame() const {
  OutputFrame f;
  f.points = cloud_.positions;
  const Index n = cloud_.size();
  auto scalar = [&](const std::string& name, const Eigen::VectorXd& v) {
    PointField field{name, 1, std::vector<Real>(v.data(), v.data() + v.size())};
    f.point_fields.push_back(std::move(field));
  };
  auto vector3 = [&](const std::string& name, const Eigen::Matrix3Xd& m) {
    f.point_fields.push_back(PointField{name, 3, std::vector<Real>(m.data(), m.data() + m.size())});
  };
  scalar("volume", cloud_.volumes);
  if (approximation_.size() == n) {
    scalar("field_exact", exact_);
    scalar("field_mls", approximation_);
    Eigen::VectorXd error = approximation_ - exact_;
    scalar("field_error", error);
    vector3("gradient_exact", exact_gradient_);
    vector3("gradient_mls", gradient_);
    f.point_fields.push_back(PointField{"hessian_mls", 6, std::vector<Real>(hessian_.data(), hessian_.data() + hessian_.size())});
  }
  return f;
}

RunCounts MlsFitAnalysis::counts() const { return RunCounts{cloud_.size(), cloud_.size(), 1}; }

}  // namespace lamina::efg
