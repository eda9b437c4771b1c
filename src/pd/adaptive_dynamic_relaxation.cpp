#include "pd/adaptive_dynamic_relaxation.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"

namespace lamina::pd {

AdaptiveDynamicRelaxation::AdaptiveDynamicRelaxation(const PeridynamicModel& solid, Eigen::VectorXd fictitious_density,
                                                     std::vector<char> free, AdaptiveDynamicRelaxationOptions options,
                                                     const RelaxationCoordinates* coordinates)
    : solid_(solid), lambda_(std::move(fictitious_density)), free_(std::move(free)), options_(options),
      coordinates_(coordinates) {}

RelaxationResult AdaptiveDynamicRelaxation::relax(PointMatrix& u, const PointMatrix& external_force,
                                                 Real reference_residual) const {
  const Index dofs = u.size();
  Eigen::Map<Eigen::VectorXd> U(u.data(), dofs);
  const Eigen::Map<const Eigen::VectorXd> fext(external_force.data(), dofs);
  // q: the relaxed coordinates (U itself, or T^-1 U); g: the force conjugate to q (F, or T^T F)
  const bool mapped = coordinates_ != nullptr;
  const std::vector<char>& free_q = mapped ? coordinates_->free : free_;
  Eigen::VectorXd q = mapped ? Eigen::VectorXd(coordinates_->from_nodes * U) : Eigen::VectorXd(U);
  Eigen::VectorXd velocity = Eigen::VectorXd::Zero(dofs), previous_force(dofs), residual(dofs), force_q(dofs),
                  residual_q(dofs);
  RelaxationResult result;
  result.state = solid_.make_state();
  const Real dt = 1.0;
  Real previous_kinetic = 0;
  bool restart = false;
  // the displacement of the damping estimate: U (seed eq (6)) or U - U_start (damping_estimate: increment)
  const bool incremental = options_.damping_estimate == AdaptiveDynamicRelaxationOptions::DampingEstimate::increment;
  const Eigen::VectorXd start = incremental ? q : Eigen::VectorXd();
  for (int k = 0;; ++k) {
    // Stage 1: internal force at U^k = T q^k.
    if (mapped && k > 0) U = coordinates_->to_nodes * q;
    solid_.update(u, *result.state);
    result.internal_force = solid_.internal_force(*result.state);
    if (complete_force_) complete_force_(result.internal_force);
    const Eigen::Map<const Eigen::VectorXd> fint(result.internal_force.data(), dofs);
    // Stage 2: residual on the free dofs and the convergence test (seed eq (8)).
    Real largest = 0, scale = 0;
    for (Index d = 0; d < dofs; ++d) {
      residual[d] = free_[static_cast<std::size_t>(d)] ? fint[d] + fext[d] : 0.0;
      largest = std::isnan(residual[d]) ? residual[d] : std::max(largest, std::abs(residual[d]));
      scale = std::max({scale, std::abs(fint[d]), std::abs(fext[d])});
    }
    if (!std::isfinite(largest) || !std::isfinite(scale))
      throw AnalysisError(fmt::format("adaptive dynamic relaxation: non-finite residual at iteration {}", k));
    if (k == 0) result.initial_residual = reference_residual > 0 ? reference_residual : largest;
    result.residual = largest;
    result.iterations = k;
    const Real absolute = options_.absolute_tolerance >= 0 ? options_.absolute_tolerance : options_.tolerance * scale;
    const bool relative_ok = largest <= options_.tolerance * result.initial_residual;
    const bool absolute_ok = k >= options_.switch_iteration && largest <= absolute;
    if (largest == 0 || relative_ok || absolute_ok) {
      result.converged = true;
      return result;
    }
    if (k >= options_.max_iterations) return result;
    if (mapped) {
      force_q = coordinates_->to_nodes.transpose() * fint;
      residual_q = coordinates_->to_nodes.transpose() * residual;
    }
    using ConstRef = Eigen::Ref<const Eigen::VectorXd>;
    const ConstRef g = mapped ? ConstRef(force_q) : ConstRef(fint);
    const ConstRef r = mapped ? ConstRef(residual_q) : ConstRef(residual);
    // Stage 3: adaptive damping from the local diagonal stiffness (seed eq (6)).
    Real c = 0;
    if (k > 0) {
      Real numerator = 0, denominator = 0;
      for (Index d = 0; d < dofs; ++d) {
        if (!free_q[static_cast<std::size_t>(d)]) continue;
        const Real ud = incremental ? q[d] - start[d] : q[d];
        denominator += ud * ud;
        const Real v = velocity[d];
        if (v == 0 || std::abs(v) < options_.velocity_guard * std::abs(q[d])) continue;
        const Real local_stiffness = -(g[d] - previous_force[d]) / (lambda_[d] * dt * v);
        numerator += ud * local_stiffness * ud;
      }
      if (denominator > 0 && numerator > 0) c = 2.0 * std::sqrt(numerator / denominator);
      if (c > 2.0) c = 1.9;
    }
    // Stage 4: velocity update (start-up half step at k = 0, central difference otherwise).
    Real dissipated = 0, kinetic = 0;
    for (Index d = 0; d < dofs; ++d) {
      if (!free_q[static_cast<std::size_t>(d)]) {
        velocity[d] = 0;
        continue;
      }
      const Real old_velocity = velocity[d];
      velocity[d] = k == 0 || restart ? 0.5 * dt * r[d] / lambda_[d]
                           : ((2.0 - c * dt) * old_velocity + 2.0 * dt * r[d] / lambda_[d]) / (2.0 + c * dt);
      const Real mean = 0.5 * (old_velocity + velocity[d]);
      dissipated += c * lambda_[d] * mean * mean * dt;
      kinetic += lambda_[d] * velocity[d] * velocity[d];
    }
    result.damping_energy += dissipated;
    // Kinetic-energy fallback: where the damping estimate is zero (negative local stiffness, e.g. a
    // snap-through), the motion would stay undamped; stop it at each peak of the kinetic energy.
    restart = false;
    if (options_.kinetic_fallback && c == 0 && k > 0 && kinetic < previous_kinetic) {
      result.damping_energy += 0.5 * kinetic;
      velocity.setZero();
      kinetic = 0;
      restart = true;  // from rest: the next velocity is the start-up half step again
    }
    previous_kinetic = kinetic;
    // Stage 5: displacement update; remember F^k for the next local stiffness.
    q += dt * velocity;
    if (!mapped) U = q;
    previous_force = g;
  }
}

}  // namespace lamina::pd
