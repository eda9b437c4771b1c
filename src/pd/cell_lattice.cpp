#include "pd/cell_lattice.hpp"

#include <cmath>

namespace lamina::pd {

CellLattice make_cell_lattice(const Vec3& lower, const Vec3& upper, const Vec3& requested_spacing) {
  CellLattice lattice;
  lattice.lower = lower;
  lattice.upper = upper;
  for (int d = 0; d < 3; ++d) {
    const Real extent = upper[d] - lower[d];
    const Index n = std::max<Index>(1, static_cast<Index>(std::llround(extent / requested_spacing[d])));
    lattice.cells[static_cast<std::size_t>(d)] = n;
    lattice.spacing[d] = extent / static_cast<Real>(n);
  }
  return lattice;
}

PointCloud lattice_point_cloud(const CellLattice& lattice, bool plate_sets) {
  const auto [nx, ny, nz] = lattice.cells;
  const Index count = nx * ny * nz;
  PointCloud cloud;
  cloud.positions.resize(3, count);
  cloud.volumes = Eigen::VectorXd::Constant(count, lattice.spacing.prod());
  cloud.spacing = lattice.spacing.replicate(1, count);
  cloud.counts = lattice.cells;
  const char* low_names[3] = {"xmin", "ymin", "zmin"};
  const char* high_names[3] = {"xmax", "ymax", "zmax"};
  for (int d = 0; d < 3; ++d) {
    cloud.sets[low_names[d]] = {};
    cloud.sets[high_names[d]] = {};
  }
  Index node = 0;
  for (Index k = 0; k < nz; ++k)
    for (Index j = 0; j < ny; ++j)
      for (Index i = 0; i < nx; ++i, ++node) {
        const std::array<Index, 3> ijk{i, j, k};
        for (int d = 0; d < 3; ++d) {
          cloud.positions(d, node) =
              lattice.lower[d] + (static_cast<Real>(ijk[static_cast<std::size_t>(d)]) + 0.5) * lattice.spacing[d];
          if (ijk[static_cast<std::size_t>(d)] == 0) cloud.sets[low_names[d]].push_back(node);
          if (ijk[static_cast<std::size_t>(d)] == lattice.cells[static_cast<std::size_t>(d)] - 1)
            cloud.sets[high_names[d]].push_back(node);
        }
      }
  if (plate_sets) {
    cloud.sets["top"] = cloud.sets["zmax"];
    cloud.sets["bottom"] = cloud.sets["zmin"];
  }
  return cloud;
}

}  // namespace lamina::pd
