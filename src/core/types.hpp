#pragma once
// Basic numeric types shared by every lamina module.
// Coordinates of point sets are stored as 3 x N Eigen matrices (one column per point).
#include <Eigen/Dense>
#include <cstdint>
#include <vector>

namespace lamina {

using Real = double;
using Index = std::int64_t;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using PointMatrix = Eigen::Matrix3Xd;  // column j = coordinates of point j
using IndexList = std::vector<Index>;

}  // namespace lamina
