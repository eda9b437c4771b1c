#include "mpm/shell_statics.hpp"

#include <Eigen/SparseLU>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <limits>

namespace lamina::mpm {

struct ShellStatics::LinearSolver {
  Eigen::SparseLU<Eigen::SparseMatrix<Real>, Eigen::COLAMDOrdering<int>> lu;
  Index pattern_nonzeros = -1;  // the pattern lu was analysed for
};

ShellStatics::~ShellStatics() = default;

ShellStatics::ShellStatics(const shell::BelytschkoTsayShell& element, const ShellMesh& mesh, const Eigen::Matrix3Xd& free,
                           const Eigen::Matrix3Xd& rotation_free)
    : element_(element), mesh_(mesh), solver_(std::make_unique<LinearSolver>()) {
  const Index n = mesh.node_count();
  equation_.resize(6, n);
  for (Index i = 0; i < n; ++i)
    for (int c = 0; c < 6; ++c) equation_(c, i) = (c < 3 ? free(c, i) : rotation_free(c - 3, i)) > 0 ? unknowns_++ : -1;
}

bool ShellStatics::element_forces(const ShellState& start, Index e, const shell::NodeMatrix& ue, const shell::NodeMatrix& te,
                                  Vec24& out, std::vector<Real>& stress, Real* hourglass, Real& thickness, Real* internal_work,
                                  Real* hourglass_work) const {
  const int size = element_.stress_size();
  std::copy(start.stress.col(e).data(), start.stress.col(e).data() + size, stress.begin());
  std::copy(start.hourglass.col(e).data(), start.hourglass.col(e).data() + shell::BelytschkoTsayShell::kHourglassSize, hourglass);
  thickness = start.thickness[e];
  shell::NodeMatrix x0;
  for (int a = 0; a < 4; ++a) x0.col(a) = start.x.col(mesh_.quads(a, e));
  // 1. stresses over the increment at the mid-increment configuration
  const shell::ShellElementResult advanced = element_.update(x0 + 0.5 * ue, ue, te, 1.0, stress.data(), hourglass, thickness);
  if (!advanced.valid) return false;
  // 2. their forces at the end configuration
  const shell::NodeMatrix zero = shell::NodeMatrix::Zero();
  const shell::ShellElementResult r = element_.update(x0 + ue, zero, zero, 0.0, stress.data(), hourglass, thickness);
  if (!r.valid || !std::isfinite(thickness) || !(thickness > 0)) return false;
  out.head<12>() = Eigen::Map<const Eigen::Matrix<Real, 12, 1>>(r.force.data());
  out.tail<12>() = Eigen::Map<const Eigen::Matrix<Real, 12, 1>>(r.moment.data());
  if (internal_work) *internal_work = advanced.internal_power;
  if (hourglass_work) *hourglass_work = advanced.hourglass_power;
  return true;
}

void ShellStatics::begin_increment(const ShellState& start) {
  const Index n = mesh_.node_count();
  drilling_spring_ = Eigen::Matrix<Real, 9, Eigen::Dynamic>::Zero(9, n);
  const Real young = element_.material().young_modulus();
  for (Index e = 0; e < mesh_.element_count(); ++e) {
    const Vec3 r31 = start.x.col(mesh_.quads(2, e)) - start.x.col(mesh_.quads(0, e));
    const Vec3 r42 = start.x.col(mesh_.quads(3, e)) - start.x.col(mesh_.quads(1, e));
    const Vec3 normal = r31.cross(r42).normalized();
    const Real h = start.thickness[e];
    const Mat3 spring = kDrillingSpring * young * h * h * h / 12.0 * normal * normal.transpose();
    if (!spring.allFinite()) continue;  // (a degenerate element fails in forces())
    for (int a = 0; a < 4; ++a) drilling_spring_.col(mesh_.quads(a, e)) += Eigen::Map<const Eigen::Matrix<Real, 9, 1>>(spring.data());
  }
}

IncrementForces ShellStatics::forces(const ShellState& start, const PointMatrix& u, const PointMatrix& theta, ShellState* end) const {
  const Index e_count = mesh_.element_count(), n = mesh_.node_count();
  const int size = element_.stress_size();
  Eigen::Matrix<Real, 24, Eigen::Dynamic> element_result(24, e_count);
  Eigen::VectorXd work(e_count), hourglass_work(e_count);
  if (end) {
    end->x = start.x + u;
    end->stress.resize(start.stress.rows(), e_count);
    end->hourglass.resize(start.hourglass.rows(), e_count);
    end->thickness.resize(e_count);
  }
  Index bad = -1;
#pragma omp parallel if (e_count > 64)
  {
    std::vector<Real> stress(static_cast<std::size_t>(size));
    std::array<Real, shell::BelytschkoTsayShell::kHourglassSize> hourglass{};
#pragma omp for schedule(static) reduction(max : bad)
    for (Index e = 0; e < e_count; ++e) {
      shell::NodeMatrix ue, te;
      for (int a = 0; a < 4; ++a) {
        ue.col(a) = u.col(mesh_.quads(a, e));
        te.col(a) = theta.col(mesh_.quads(a, e));
      }
      Vec24 f;
      Real h = 0;
      if (!element_forces(start, e, ue, te, f, stress, hourglass.data(), h, &work[e], &hourglass_work[e])) {
        bad = std::max(bad, e);
        continue;
      }
      element_result.col(e) = f;
      if (end) {
        std::copy(stress.begin(), stress.end(), end->stress.col(e).data());
        std::copy(hourglass.begin(), hourglass.end(), end->hourglass.col(e).data());
        end->thickness[e] = h;
      }
    }
  }
  IncrementForces out;
  out.invalid_element = bad;
  out.force = Eigen::Matrix3Xd::Zero(3, n);
  out.moment = Eigen::Matrix3Xd::Zero(3, n);
  if (bad >= 0) return out;
  for (Index e = 0; e < e_count; ++e) {  // in element order: the same sums on any thread count
    for (int a = 0; a < 4; ++a) {
      out.force.col(mesh_.quads(a, e)) += element_result.block<3, 1>(3 * a, e);
      out.moment.col(mesh_.quads(a, e)) += element_result.block<3, 1>(12 + 3 * a, e);
    }
    out.internal_work += work[e];
    out.hourglass_work += hourglass_work[e];
  }
  for (Index i = 0; i < n; ++i) {  // the drilling springs (work 1/2 theta . S theta over the increment)
    const Eigen::Map<const Mat3> spring(drilling_spring_.col(i).data());
    const Vec3 moment = spring * theta.col(i);
    out.moment.col(i) += moment;
    out.hourglass_work += 0.5 * theta.col(i).dot(moment);
  }
  return out;
}

Eigen::SparseMatrix<Real> ShellStatics::tangent(const ShellState& start, const PointMatrix& u, const PointMatrix& theta) const {
  const Index e_count = mesh_.element_count();
  const int size = element_.stress_size();
  std::vector<Eigen::Matrix<Real, 24, 24>> blocks(static_cast<std::size_t>(e_count));
#pragma omp parallel if (e_count > 16)
  {
    std::vector<Real> stress(static_cast<std::size_t>(size));
    std::array<Real, shell::BelytschkoTsayShell::kHourglassSize> hourglass{};
#pragma omp for schedule(static)
    for (Index e = 0; e < e_count; ++e) {
      shell::NodeMatrix ue, te, x0;
      for (int a = 0; a < 4; ++a) {
        ue.col(a) = u.col(mesh_.quads(a, e));
        te.col(a) = theta.col(mesh_.quads(a, e));
        x0.col(a) = start.x.col(mesh_.quads(a, e));
      }
      const Real diagonal = std::max((x0.col(2) - x0.col(0)).norm(), (x0.col(3) - x0.col(1)).norm());
      Vec24 forward, backward;
      Real h = 0;
      auto& block = blocks[static_cast<std::size_t>(e)];
      for (int j = 0; j < 24; ++j) {
        shell::NodeMatrix up = ue, tp = te, um = ue, tm = te;
        const Real step = j < 12 ? 1e-6 * diagonal : 1e-6;
        (j < 12 ? up : tp)(j % 3, (j % 12) / 3) += step;
        (j < 12 ? um : tm)(j % 3, (j % 12) / 3) -= step;
        if (!element_forces(start, e, up, tp, forward, stress, hourglass.data(), h, nullptr, nullptr) ||
            !element_forces(start, e, um, tm, backward, stress, hourglass.data(), h, nullptr, nullptr)) {
          block.setZero();  // (forces() reports the element; the pattern stays the same)
          break;
        }
        block.col(j) = (forward - backward) / (2 * step);
      }
    }
  }
  // rows / columns of the 24 element entries: node a's translations 3a..3a+2, rotations 12+3a..
  std::vector<Eigen::Triplet<Real>> entries;
  entries.reserve(static_cast<std::size_t>(e_count) * 24 * 24);
  for (Index e = 0; e < e_count; ++e) {
    Index rows[24];
    for (int k = 0; k < 24; ++k) {
      const int a = (k % 12) / 3, c = k % 3 + (k < 12 ? 0 : 3);
      rows[k] = equation_(c, mesh_.quads(a, e));
    }
    const auto& block = blocks[static_cast<std::size_t>(e)];
    for (int j = 0; j < 24; ++j) {
      if (rows[j] < 0) continue;
      for (int i = 0; i < 24; ++i)
        if (rows[i] >= 0) entries.emplace_back(static_cast<int>(rows[i]), static_cast<int>(rows[j]), block(i, j));  // zeros too: one pattern
    }
  }
  for (Index i = 0; i < mesh_.node_count(); ++i)  // the drilling springs
    for (int b = 0; b < 3; ++b)
      for (int a = 0; a < 3; ++a)
        if (equation_(3 + a, i) >= 0 && equation_(3 + b, i) >= 0)
          entries.emplace_back(static_cast<int>(equation_(3 + a, i)), static_cast<int>(equation_(3 + b, i)), drilling_spring_(3 * b + a, i));
  Eigen::SparseMatrix<Real> k(unknowns_, unknowns_);
  k.setFromTriplets(entries.begin(), entries.end());
  return k;
}

bool ShellStatics::solve(const Eigen::SparseMatrix<Real>& k, const Eigen::VectorXd& r, Eigen::VectorXd& x, std::string& reason) {
  LinearSolver& s = *solver_;
  if (s.pattern_nonzeros != k.nonZeros()) {
    s.lu.analyzePattern(k);
    s.pattern_nonzeros = k.nonZeros();
  }
  s.lu.factorize(k);
  if (s.lu.info() != Eigen::Success) {
    s.pattern_nonzeros = -1;
    reason = fmt::format("the tangent is singular ({})", s.lu.lastErrorMessage());
    return false;
  }
  x = s.lu.solve(r);
  const Real miss = (k * x - r).norm() / std::max(r.norm(), std::numeric_limits<Real>::min());
  if (!x.allFinite() || !(miss < 0.1)) {
    reason = fmt::format("the tangent is nearly singular (the solution misses by {:.3g})", miss);
    return false;
  }
  return true;
}

}  // namespace lamina::mpm
