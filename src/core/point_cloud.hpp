#pragma once
// A set of nodes/particles filling a body: positions, the volume each one represents, and
// named node sets (faces, edges) that case files refer to with {set: NAME}.
#include <array>
#include <map>
#include <string>

#include "core/types.hpp"

namespace lamina {

struct PointCloud {
  PointMatrix positions;                    // 3 x N reference coordinates
  Eigen::VectorXd volumes;                  // N tributary volumes; sum = body volume
  Eigen::Matrix3Xd parametric;              // 3 x N mapped coordinates (may be empty)
  std::array<Index, 3> counts{0, 0, 0};     // structured counts per direction (0 if unstructured)
  Eigen::Matrix3Xd spacing;                 // 3 x N local nodal spacing along x, y, z (for MLS kappa)
  std::map<std::string, IndexList> sets;    // named node sets

  Index size() const { return positions.cols(); }
  Vec3 point(Index i) const { return positions.col(i); }
};

}  // namespace lamina
