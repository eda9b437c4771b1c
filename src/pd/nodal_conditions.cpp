#include "pd/nodal_conditions.hpp"

#include <cstdint>
#include <map>
#include <optional>

#include "geometry/expression.hpp"

namespace lamina::pd {

void apply_conditions(const std::vector<model::Constraint>& constraints, const std::vector<model::Load>& loads,
                      PeridynamicProblem& p, std::vector<Diagnostic>& problems) {
  const Index n = p.positions.cols();
  // Ramps.
  auto ramp_index = [&](const Ramp& r) -> int {
    if (r.kind == Ramp::Kind::linear) return -1;
    p.ramps.push_back(r);
    return static_cast<int>(p.ramps.size()) - 1;
  };
  // Boundary conditions (a later condition on the same dof replaces an earlier one).
  std::map<Index, std::size_t> seen;
  std::map<Index, std::uint8_t> held_axes;  // rotations held, per node
  auto prescribe = [&](const PrescribedDof& d) {
    const Index key = 3 * d.node + d.component;
    auto it = seen.find(key);
    if (it == seen.end()) {
      seen[key] = p.prescribed.size();
      p.prescribed.push_back(d);
    } else {
      p.prescribed[it->second] = d;
    }
  };
  for (const auto& b : constraints) {
    const int ramp = ramp_index(b.ramp);
    int step_ramp = -1;  // velocities default to a step (constant): one ramp for the whole condition
    for (int a = 0; a < 3; ++a) {
      const auto A = static_cast<std::size_t>(a);
      if (b.velocity[A] && p.analysis != PdAnalysisKind::explicit_dynamics) {
        problems.push_back(model::diagnostic_at(
            b.location, ".velocity", "fix, symmetry or displacement (velocity needs pd.analysis: explicit)", "velocity"));
        continue;
      }
      if (!b.fixed[A] && !b.displacement[A] && !b.velocity[A]) continue;
      // the prescribed value's field, parsed once for all the nodes
      std::optional<geometry::FieldEvaluator> value;
      try {
        if (b.velocity[A]) value.emplace(*b.velocity[A], 0.0);
        else if (b.displacement[A]) value.emplace(*b.displacement[A], 0.0);
      } catch (const geometry::ExpressionError& e) {
        problems.push_back(model::diagnostic_at(b.location, ".displacement", "a valid expression of x, y, z", e.what()));
        continue;
      }
      if (b.velocity[A] && b.ramp.kind == Ramp::Kind::linear && step_ramp < 0) {
        step_ramp = static_cast<int>(p.ramps.size());
        p.ramps.push_back(Ramp{Ramp::Kind::step, {}});
      }
      for (Index i : b.select.nodes) {
        PrescribedDof d;
        d.node = i;
        d.component = a;
        d.ramp = ramp;
        if (b.velocity[A]) {
          d.velocity = true;
          d.value = (*value)(p.positions.col(i));
          if (b.ramp.kind == Ramp::Kind::linear) d.ramp = step_ramp;
        } else if (value) {
          d.value = (*value)(p.positions.col(i));
        }
        prescribe(d);
      }
    }
    // rotations: kept for the one-layer plate model (the analysis refuses them on any other body)
    std::uint8_t axes = 0;
    for (int a = 0; a < 3; ++a)
      if (b.fixed[static_cast<std::size_t>(3 + a)]) axes |= static_cast<std::uint8_t>(1 << a);
    if (axes) {
      if (!p.held_rotations.where)
        p.held_rotations.where = model::diagnostic_at(
            b.location, ".fix", "translations x, y or z: peridynamic nodes have no rotations (they are held only on a "
            "one-layer plate, through its normal; a 2-4 layer plate is clamped by holding x, y, z of every layer)",
            "rotations");
      for (Index i : b.select.nodes) held_axes[i] |= axes;
    }
  }
  for (const auto& [node, axes] : held_axes) {
    p.held_rotations.nodes.push_back(node);
    p.held_rotations.axes.push_back(axes);
  }
  // Loads.
  for (const auto& l : loads) {
    const auto& nodes = l.select.nodes;
    const int ramp = ramp_index(l.ramp);
    try {
      // the load's fields, parsed once for all the nodes
      const geometry::FieldEvaluator fx(l.vector[0], 0.0), fy(l.vector[1], 0.0), fz(l.vector[2], 0.0);
      auto vector_at = [&](Index i) {
        const Vec3 x = p.positions.col(i);
        return Vec3(fx(x), fy(x), fz(x));
      };
      switch (l.kind) {
        case model::Load::Kind::force:
          for (Index i : nodes) p.forces.push_back(NodalForce{i, vector_at(i) / static_cast<Real>(nodes.size()), ramp});
          break;
        case model::Load::Kind::body_force:
          for (Index i : nodes) p.forces.push_back(NodalForce{i, vector_at(i) * p.volumes[i], ramp});
          break;
        case model::Load::Kind::initial_velocity:
          if (p.initial_velocity.cols() != n) p.initial_velocity = PointMatrix::Zero(3, n);
          for (Index i : nodes) p.initial_velocity.col(i) = vector_at(i);
          break;
        default:
          problems.push_back(model::diagnostic_at(l.location, "", "force, body_force or initial_velocity (pd applies loads at nodes)",
                                                  "traction, pressure or mass"));
      }
    } catch (const geometry::ExpressionError& e) {
      problems.push_back(model::diagnostic_at(l.location, "", "a valid expression of x, y, z", e.what()));
    }
  }
}

}  // namespace lamina::pd
