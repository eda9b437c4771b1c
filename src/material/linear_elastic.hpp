#pragma once
// Isotropic linear elasticity in 3D (Voigt notation, engineering shear strains):
//   strain  = [exx, eyy, ezz, gxy, gyz, gzx]  (gxy = 2 exy)
//   stress  = [sxx, syy, szz, sxy, syz, szx]  = D strain
// Order xx yy zz xy yz zx everywhere (the same as VTU fields and probe components).
#include <string>

#include "core/types.hpp"

namespace lamina::material {

using Voigt = Eigen::Matrix<Real, 6, 1>;
using VoigtMatrix = Eigen::Matrix<Real, 6, 6>;

struct LinearElastic {
  Real E = 0.0;
  Real nu = 0.0;

  // The moduli, computed here and nowhere else.
  Real lambda() const { return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)); }
  Real mu() const { return E / (2.0 * (1.0 + nu)); }
  Real bulk_modulus() const { return E / (3.0 * (1.0 - 2.0 * nu)); }
  /// P-wave (constrained) modulus lambda + 2 mu: the largest eigenvalue scale of D.
  Real p_wave_modulus() const { return lambda() + 2.0 * mu(); }
  /// Plane-stress modulus E / (1 - nu^2) (membrane stiffness per thickness, D = E' t^3 / 12).
  Real plane_stress_modulus() const { return E / (1.0 - nu * nu); }
  /// Its off-diagonal term nu E / (1 - nu^2).
  Real plane_stress_coupling() const { return nu * E / (1.0 - nu * nu); }

  /// 3 x 3 plane-stress matrix [xx yy xy] with engineering shear: E' [[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]].
  Mat3 plane_stress_matrix() const;

  /// 6 x 6 elasticity matrix D.
  VoigtMatrix matrix() const;
  /// stress = D strain (engineering shear strains in, tensor shear stresses out).
  Voigt stress(const Voigt& strain) const;
  /// Strain energy density 1/2 strain . D strain.
  Real energy_density(const Voigt& strain) const;

  /// Throws InputError at key_path if E <= 0 or nu outside (-1, 0.5).
  void validate(const std::string& key_path) const;
};

/// Strain (engineering shear) from a displacement gradient G (G(i, j) = du_i / dx_j).
Voigt strain_from_gradient(const Mat3& G);
/// von Mises equivalent stress of a Voigt stress vector.
Real von_mises(const Voigt& stress);
/// Traction t = sigma n of a Voigt stress vector.
Vec3 traction(const Voigt& stress, const Vec3& n);

}  // namespace lamina::material
