#pragma once
// Error raised when the MLS moment matrix A(x) (seed 004, eqs 1-4..1-19) is singular or ill-conditioned at an
// evaluation point (too few or badly placed neighbours for the basis; seed: SINCHECK).
#include <string>

#include "core/error.hpp"
#include "core/types.hpp"

namespace lamina::mls {

class SingularMomentMatrix : public AnalysisError {
 public:
  SingularMomentMatrix(const std::string& message, const Vec3& point, Index neighbours, int basis_size,
                       Real condition)
      : AnalysisError(message), point_(point), neighbours_(neighbours), basis_size_(basis_size),
        condition_(condition) {}

  const Vec3& point() const { return point_; }
  Index neighbours() const { return neighbours_; }
  int basis_size() const { return basis_size_; }
  /// Estimated condition number (infinity when A was not even positive definite).
  Real condition() const { return condition_; }

 private:
  Vec3 point_;
  Index neighbours_;
  int basis_size_;
  Real condition_;
};

}  // namespace lamina::mls
