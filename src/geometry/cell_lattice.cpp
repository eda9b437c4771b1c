#include "geometry/cell_lattice.hpp"

#include <cmath>
#include <vector>

#include "core/gauss_legendre.hpp"

namespace lamina::geometry {

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

PointCloud lattice_point_cloud(const CellLattice& lattice, bool plate_sets, bool gauss_layers) {
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
  Eigen::VectorXd layer_z(nz), layer_weight = Eigen::VectorXd::Ones(nz);
  for (Index k = 0; k < nz; ++k) layer_z[k] = lattice.lower.z() + (static_cast<Real>(k) + 0.5) * lattice.spacing.z();
  if (gauss_layers) {
    std::vector<Real> points, weights;
    gauss_legendre(static_cast<int>(nz), points, weights);
    const Real centre = 0.5 * (lattice.lower.z() + lattice.upper.z()), half = 0.5 * (lattice.upper.z() - lattice.lower.z());
    for (Index k = 0; k < nz; ++k) {
      layer_z[k] = centre + half * points[static_cast<std::size_t>(k)];
      layer_weight[k] = 0.5 * static_cast<Real>(nz) * weights[static_cast<std::size_t>(k)];  // relative to the cell volume
    }
  }
  Index node = 0;
  for (Index k = 0; k < nz; ++k)
    for (Index j = 0; j < ny; ++j)
      for (Index i = 0; i < nx; ++i, ++node) {
        const std::array<Index, 3> ijk{i, j, k};
        for (int d = 0; d < 3; ++d) {
          cloud.positions(d, node) =
              d == 2 ? layer_z[k] : lattice.lower[d] + (static_cast<Real>(ijk[static_cast<std::size_t>(d)]) + 0.5) * lattice.spacing[d];
          if (ijk[static_cast<std::size_t>(d)] == 0) cloud.sets[low_names[d]].push_back(node);
          if (ijk[static_cast<std::size_t>(d)] == lattice.cells[static_cast<std::size_t>(d)] - 1)
            cloud.sets[high_names[d]].push_back(node);
        }
      }
  if (gauss_layers)
    for (Index k = 0, index = 0; k < nz; ++k)
      for (Index j = 0; j < nx * ny; ++j, ++index) cloud.volumes[index] *= layer_weight[k];
  if (plate_sets) {
    cloud.sets["top"] = cloud.sets["zmax"];
    cloud.sets["bottom"] = cloud.sets["zmin"];
  }
  return cloud;
}

}  // namespace lamina::geometry
