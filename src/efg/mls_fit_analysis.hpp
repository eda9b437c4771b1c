#pragma once
// `method: mls_fit` — fits an analytic field with MLS on the case's nodes and reports the
// relative errors errU, errDU, errDDU (in percent) of seed 004 eqs (3-3)-(3-5).
#include <memory>
#include <string>

#include "core/analysis.hpp"
#include "core/point_cloud.hpp"
#include "mls/mls_shape_functions.hpp"

namespace lamina::efg {

struct MlsFitOptions {
  std::string field;             // muParser expression in x, y, z
  mls::MlsOptions mls;
  Real difference_step = 1e-3;   // relative step (times the body size) of the derivative stencil
};

class MlsFitAnalysis : public Analysis {
 public:
  MlsFitAnalysis(PointCloud cloud, MlsFitOptions options, std::vector<Probe> probes);

  std::string method() const override { return "mls_fit"; }
  void run(OutputSink& sink) override;
  Real probe(const Probe& probe) const override;
  std::map<std::string, Real> builtin_probes() const override;
  OutputFrame frame() const override;
  RunCounts counts() const override;
  std::map<std::string, Real> timings() const override { return timings_; }

 private:
  PointCloud cloud_;
  MlsFitOptions options_;
  Eigen::VectorXd nodal_values_;
  Eigen::VectorXd approximation_, exact_;           // at the nodes
  Eigen::Matrix3Xd gradient_, exact_gradient_;      // 3 x N
  Eigen::Matrix<Real, 6, Eigen::Dynamic> hessian_, exact_hessian_;  // xx yy zz xy yz zx
  Real error_value_ = 0, error_gradient_ = 0, error_hessian_ = 0;
  std::map<std::string, Real> timings_;
  std::unique_ptr<mls::MlsShapeFunctions> shape_functions_;
};

/// Value, gradient and Hessian (xx yy zz xy yz zx) of an expression by 4th-order central differences.
struct FieldDerivatives {
  Real value;
  Vec3 gradient;
  Eigen::Matrix<Real, 6, 1> hessian;
};
FieldDerivatives differentiate_expression(const std::string& expression, const Vec3& x, Real step);

}  // namespace lamina::efg
