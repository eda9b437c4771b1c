#include "mpfem/particle_conditions.hpp"

#include <fmt/format.h>

#include <cmath>
#include <optional>

#include "geometry/expression.hpp"

namespace lamina::mpfem {

std::vector<PrescribedDof> prescribed_dofs(const std::vector<model::Constraint>& constraints, const PointMatrix& positions,
                                           std::vector<Diagnostic>& problems) {
  std::vector<PrescribedDof> prescribed;
  for (const auto& b : constraints) {
    if (b.velocity[0] || b.velocity[1] || b.velocity[2]) {
      problems.push_back(model::diagnostic_at(b.location, ".velocity", "fix, symmetry or displacement (velocity is for explicit methods)",
                                              "velocity"));
      continue;
    }
    bool any = false;
    for (int a = 0; a < 2; ++a) {
      const bool fixed = b.fixed[static_cast<std::size_t>(a)];
      const auto& value = b.displacement[static_cast<std::size_t>(a)];
      if (!fixed && !value) continue;
      any = true;
      std::optional<geometry::FieldEvaluator> field;
      if (value) field.emplace(*value, 1.0);
      for (Index q : b.select.nodes) {
        PrescribedDof d;
        d.node = q;
        d.component = a;
        if (field) d.value = (*field)(positions.col(q));
        if (!std::isfinite(d.value)) {
          problems.push_back(model::diagnostic_at(b.location, ".displacement", "a finite prescribed displacement",
                                                  fmt::format("{} at particle {}", d.value, q)));
          break;
        }
        prescribed.push_back(d);
      }
    }
    if (!any)
      problems.push_back(model::diagnostic_at(b.location, ".fix", "x or y (mpfem is 2D: z and rotations are ignored)", "neither x nor y"));
  }
  return prescribed;
}

}  // namespace lamina::mpfem
