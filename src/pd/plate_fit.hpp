#pragma once
// Polynomial least-squares derivatives over a node column's in-plane family, shared by the plate models
// (peridynamic_plate.hpp, kirchhoff_plate.hpp): f_j - f_i = sum of the monomials of degree 1..3 of the
// reference bond xi_b, weighted by v_b; the fit's coefficients give grad f and (degree >= 2) the second
// derivatives at the column itself (a higher-order correspondence, as in the peridynamic differential
// operator of Madenci et al. 2016 and the peridynamic Kirchhoff-Love shell of Behzadinasab et al. 2022).
#include <memory>

#include "core/types.hpp"
#include "pd/peridynamic_body.hpp"

namespace lamina::pd {

/// Fits of the family with bonds xi (2 x count) and weights v (count): the highest degree <= max_degree
/// (3, 2, else 1) that the family carries (at least terms + 2 bonds, Gram matrix condition below 1e7).
/// Writes first (2 x count): grad f = sum_b v_b (f_j - f_i) first_b; if second is given and the degree is
/// at least 2, second (3 x count): (f_,xx, f_,yy, f_,xy) = sum_b v_b (f_j - f_i) second_b. Returns the degree.
int plate_fit_weights(const Eigen::Matrix2Xd& xi, const Eigen::VectorXd& v, Real horizon, int max_degree,
                      Eigen::Matrix2Xd& first, Eigen::Matrix3Xd* second = nullptr);

/// The in-plane families of the node columns (centres: 3 x C, z ignored): a plane-stress body over the
/// column centres with the case's horizon and influence, cells of the columns' in-plane size.
std::unique_ptr<PeridynamicBody> column_families(const PointMatrix& centres, const Eigen::VectorXd& volumes,
                                                 const Eigen::VectorXd& young, const Eigen::VectorXd& poisson,
                                                 const BodyOptions& options, Real thickness);

}  // namespace lamina::pd
