#include "material/linear_elastic.hpp"

#include <cmath>

#include <fmt/format.h>

#include "core/error.hpp"

namespace lamina::material {

VoigtMatrix LinearElastic::matrix() const {
  const Real l = lambda(), m = mu();
  VoigtMatrix D = VoigtMatrix::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) D(i, j) = l;
    D(i, i) = l + 2.0 * m;
    D(3 + i, 3 + i) = m;
  }
  return D;
}

Mat3 LinearElastic::plane_stress_matrix() const {
  const Real f = plane_stress_modulus();
  Mat3 c;
  c << f, f * nu, 0, f * nu, f, 0, 0, 0, f * (1 - nu) / 2;
  return c;
}

Voigt LinearElastic::stress(const Voigt& e) const {
  const Real l = lambda(), m = mu();
  const Real trace = e[0] + e[1] + e[2];
  Voigt s;
  for (int i = 0; i < 3; ++i) {
    s[i] = l * trace + 2.0 * m * e[i];
    s[3 + i] = m * e[3 + i];
  }
  return s;
}

Real LinearElastic::energy_density(const Voigt& strain) const { return 0.5 * strain.dot(stress(strain)); }

void LinearElastic::validate(const std::string& key_path) const {
  if (!(E > 0.0) || !std::isfinite(E)) throw InputError(key_path + ".E", "a positive Young's modulus", fmt::format("{}", E));
  if (!(nu > -1.0 && nu < 0.5))
    throw InputError(key_path + ".nu", "a Poisson's ratio in (-1, 0.5)", fmt::format("{}", nu));
}

Voigt strain_from_gradient(const Mat3& G) {
  Voigt e;
  e << G(0, 0), G(1, 1), G(2, 2), G(0, 1) + G(1, 0), G(1, 2) + G(2, 1), G(2, 0) + G(0, 2);
  return e;
}

Real von_mises(const Voigt& s) {
  const Real a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
}

Vec3 traction(const Voigt& s, const Vec3& n) {
  return Vec3(s[0] * n[0] + s[3] * n[1] + s[5] * n[2], s[3] * n[0] + s[1] * n[1] + s[4] * n[2],
              s[5] * n[0] + s[4] * n[1] + s[2] * n[2]);
}

}  // namespace lamina::material
