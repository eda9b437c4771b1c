// `mpm.solver: newton` (the quasi-static default): each load level of MpmAnalysis solved for static
// equilibrium by Newton's method on the shell nodes (ShellStatics, shell_statics.hpp) in automatic
// sub-increments. The explicit quasi-static path (damped dynamics on the physical masses) needs about
// L^2 / (t h) steps per level on a thin flexible shell (docs/mpm.md, "Newton quasi-static solver");
// Newton needs a few tangent solves per sub-increment.
//
// One sub-increment from the last converged state to the load factor `target`:
//   start       from the converged state (u = 0, theta = 0);
//   iterate     forces -> residual r = f_ext - f_int -> converged if the residual ratio (the explicit
//               path's measure) is below mpm.tolerance -> tangent K -> K du = r -> the correction, scaled
//               so that no node rotates by more than kMaxCorrectionRotation;
//   accept      if converged within kMaxIterations and no node rotated by more than kMaxRotation over the
//               sub-increment (the accuracy of the incremental stress update); then the next one grows by
//               1.5 if it took at most 7 iterations; otherwise it is halved (at most kMaxHalvings times).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "mpm/mpm_analysis.hpp"
#include "mpm/shell_statics.hpp"

namespace lamina::mpm {

namespace {
constexpr int kMaxIterations = 15;             // per sub-increment (then the sub-increment is halved)
constexpr int kMaxHalvings = 12;               // a level in at most 2^12 sub-increments
constexpr Real kMaxRotation = 0.15;            // rad per sub-increment at any node
constexpr Real kMaxCorrectionRotation = 0.1;   // rad per Newton correction at any node
constexpr Real kJumpEnergyGap = 0.25;          // share of a sub-increment's work not stored ...
constexpr Real kJumpRateRatio = 3.0;           // ... and displacement per unit load 3 x the last one's: a jump
}  // namespace

std::pair<Real, Real> MpmAnalysis::weighted_residual(const Eigen::Matrix3Xd& f_int, const Eigen::Matrix3Xd& m_int) const {
  Real r2 = 0, ext2 = 0, int2 = 0;
  for (Index i = 0; i < x_.cols(); ++i) {
    r2 += (f_ext_.col(i) - f_int.col(i)).cwiseProduct(free_.col(i)).squaredNorm() / mass_[i] +
          (m_ext_.col(i) - m_int.col(i)).cwiseProduct(rotation_free_.col(i)).squaredNorm() / inertia_[i];
    ext2 += f_ext_.col(i).squaredNorm() / mass_[i] + m_ext_.col(i).squaredNorm() / inertia_[i];
    int2 += f_int.col(i).cwiseProduct(free_.col(i)).squaredNorm() / mass_[i] +
            m_int.col(i).cwiseProduct(rotation_free_.col(i)).squaredNorm() / inertia_[i];
  }
  return {r2, std::max({ext2, int2, std::numeric_limits<Real>::min()})};
}

bool MpmAnalysis::solve_level_newton(Real from, Real to, OutputSink& sink) {
  const MpmOptions& o = problem_.options;
  if (!statics_) statics_ = std::make_unique<ShellStatics>(*element_, problem_.mesh, free_, rotation_free_);
  ShellStatics& statics = *statics_;
  const Index n = x_.cols();
  ShellState start{x_, stress_, hourglass_, thickness_};
  compute_external_forces(from);
  Eigen::Matrix3Xd f_ext_start = f_ext_, m_ext_start = m_ext_;  // the loads of the last converged state
  Real reached = from;
  Real step = newton_step_ > 0 ? std::min(newton_step_, to - from) : to - from;
  const Real smallest = (to - from) / std::pow(2.0, kMaxHalvings);
  std::string failure;

  // forces at the increment (u, theta) from `start` at load factor `target`; residual ratio and norm
  auto evaluate = [&](Real target, const PointMatrix& u, const PointMatrix& theta, IncrementForces& out, Real& ratio,
                      Real& norm) {
    const auto clock = Clock::now();
    x_ = start.x + u;  // follower loads (pressure) act on the current configuration
    compute_external_forces(target);
    out = statics.forces(start, u, theta, nullptr);
    newton_time_[0] += seconds_since(clock);
    if (out.invalid_element >= 0) {
      failure = fmt::format("element {} became degenerate or inverted", out.invalid_element);
      return false;
    }
    const auto [r2, scale] = weighted_residual(out.force, out.moment);
    ratio = std::sqrt(r2 / scale);
    norm = std::sqrt(r2);
    if (!std::isfinite(ratio)) failure = "the residual is not finite";
    return std::isfinite(ratio);
  };

  while (reached < to - 1e-14 * std::abs(to)) {
    const Real target = std::min(to, reached + step);
    statics.begin_increment(start);
    // (no extrapolated predictor: a linear extrapolation of a rotating thin shell stretches its
    // mid-surface, a residual 1e6 x the load's; starting from the converged state costs fewer iterations)
    PointMatrix u = PointMatrix::Zero(3, n), theta = PointMatrix::Zero(3, n);
    IncrementForces f;
    Real ratio = 1, norm = 0;
    bool ok = evaluate(target, u, theta, f, ratio, norm);
    bool converged = false;
    int iteration = 0;
    for (; ok; ++iteration) {
      if ((iteration > 0 || norm == 0) && ratio < o.tolerance) {
        converged = true;
        break;
      }
      if (statics.unknowns() == 0) {
        converged = true;
        break;
      }
      if (iteration == kMaxIterations) {
        failure = fmt::format("residual ratio {:.3g} after {} iterations", ratio, kMaxIterations);
        break;
      }
      Eigen::VectorXd residual(statics.unknowns()), correction;
      for (Index i = 0; i < n; ++i)
        for (int c = 0; c < 6; ++c) {
          const Index row = statics.equation(i, c);
          if (row >= 0) residual[row] = c < 3 ? f_ext_(c, i) - f.force(c, i) : m_ext_(c - 3, i) - f.moment(c - 3, i);
        }
      auto clock = Clock::now();
      const Eigen::SparseMatrix<Real> k = statics.tangent(start, u, theta);
      newton_time_[1] += seconds_since(clock);
      clock = Clock::now();
      ok = statics.solve(k, residual, correction, failure);
      newton_time_[2] += seconds_since(clock);
      if (!ok) break;
      PointMatrix du = PointMatrix::Zero(3, n), dtheta = PointMatrix::Zero(3, n);
      for (Index i = 0; i < n; ++i)
        for (int c = 0; c < 6; ++c) {
          const Index row = statics.equation(i, c);
          if (row >= 0) (c < 3 ? du(c, i) : dtheta(c - 3, i)) = correction[row];
        }
      // No residual line search: the linearised correction of a thin shell leaves out the membrane
      // stretch its own rotation causes (the residual grows ~ alpha^2 along it), which the next
      // correction removes; only the rotation per correction is limited.
      const Real largest_rotation = dtheta.cwiseAbs().maxCoeff();
      const Real alpha = largest_rotation > kMaxCorrectionRotation ? kMaxCorrectionRotation / largest_rotation : 1.0;
      u += alpha * du;
      theta += alpha * dtheta;
      ++newton_iterations_;
      ++steps_;
      ok = evaluate(target, u, theta, f, ratio, norm);
    }
    const Real rotation = theta.cwiseAbs().maxCoeff();
    if (converged && (rotation <= kMaxRotation || step <= smallest)) {
      // the sub-increment's advanced element state and energies; its external work by the trapezoidal
      // rule (exact for loads linear along the increment)
      ShellState end;
      const auto clock = Clock::now();
      const IncrementForces done = statics.forces(start, u, theta, &end);
      newton_time_[0] += seconds_since(clock);
      Real work = 0;
      for (Index i = 0; i < n; ++i)
        work += (0.5 * (f_ext_.col(i) + f_ext_start.col(i))).dot(u.col(i)) +
                (0.5 * (m_ext_.col(i) + m_ext_start.col(i))).dot(theta.col(i));
      // A static path under load control is continuous: the sub-increment's external work and the energy
      // it stored agree to second order. Newton converging on another branch across a limit point (a
      // snap-through without its dynamics) leaves a gap of the order of the work itself, and a jump in the
      // displacement per unit load. A stiffening path (a membrane taking up a transverse load, u ~ P^(1/3))
      // also leaves a trapezoidal-rule gap, but its displacement per unit load falls: so both are asked
      // for. Such a sub-increment is refused and halved, so Newton closes in on the limit point, stops
      // there, and the snap is left to explicit dynamics.
      const Real stored = done.internal_work + done.hourglass_work;
      const Real gap = (work - stored) / std::max({std::abs(work), std::abs(stored), std::numeric_limits<Real>::min()});
      const Real rate = u.cwiseAbs().maxCoeff() / (target - reached);
      if (gap > kJumpEnergyGap && newton_last_rate_ > 0 && rate > kJumpRateRatio * newton_last_rate_) {
        if (newton_jumps_++ == 0) newton_first_jump_load_ = reached;
        failure = fmt::format("between load factors {:.6g} and {:.6g} it converges only on another branch, {:.0f} % of "
                              "the work into no stored energy: a limit point",
                              reached, target, 100 * gap);
        if (step <= smallest) break;
        step *= 0.5;
        continue;
      }
      newton_largest_gap_ = std::max(newton_largest_gap_, gap);
      newton_last_rate_ = rate;
      energy_.internal += done.internal_work;
      energy_.hourglass += done.hourglass_work;
      energy_.external += work;
      f_ext_start = f_ext_;
      m_ext_start = m_ext_;
      start = std::move(end);
      f_int_ = done.force;
      m_int_ = done.moment;
      residual_ratio_ = ratio;
      reached = target;
      ++newton_increments_;
      if (iteration <= 7 && rotation < 0.5 * kMaxRotation) step *= 1.5;
      else if (iteration > 11) step *= 0.7;
      step = std::min(step, to - from);
      sink.progress(reached, fmt::format("load {:.4g} residual {:.2e} ({} iterations)", reached, ratio, iteration));
    } else {
      if (converged) failure = fmt::format("a node rotates by {:.3g} rad in the smallest sub-increment", rotation);
      if (step <= smallest) break;
      step *= 0.5;
    }
  }
  // the last converged state (the level's end, or where Newton stopped)
  x_ = start.x;
  stress_ = start.stress;
  hourglass_ = start.hourglass;
  thickness_ = start.thickness;
  v_.setZero();
  vpos_.setZero();
  omega_.setZero();
  newton_step_ = step;
  if (reached >= to - 1e-14 * std::abs(to)) {
    compute_external_forces(to);
    return true;
  }
  if (newton_stopped_levels_++ == 0) newton_first_stop_load_ = reached;
  newton_step_ = 0;
  newton_last_rate_ = 0;
  sink.notice(fmt::format("Newton stopped at load factor {:.6g} ({}); the level to {:.6g} goes on by explicit dynamics",
                          reached, failure, to));
  locate_grid();
  return false;
}

}  // namespace lamina::mpm
