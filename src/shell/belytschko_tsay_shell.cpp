#include "shell/belytschko_tsay_shell.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lamina::shell {

using Row4 = Eigen::Matrix<Real, 1, 4>;

ThroughThicknessRule ThroughThicknessRule::lobatto(int n) {
  ThroughThicknessRule r;
  switch (n) {
    case 1: r.points = {0.0}; r.weights = {2.0}; break;
    case 2: r.points = {-1.0, 1.0}; r.weights = {1.0, 1.0}; break;
    case 3: r.points = {-1.0, 0.0, 1.0}; r.weights = {1.0 / 3.0, 4.0 / 3.0, 1.0 / 3.0}; break;
    case 4: {
      const Real a = std::sqrt(1.0 / 5.0);
      r.points = {-1.0, -a, a, 1.0};
      r.weights = {1.0 / 6.0, 5.0 / 6.0, 5.0 / 6.0, 1.0 / 6.0};
      break;
    }
    case 5: {
      const Real a = std::sqrt(3.0 / 7.0);
      r.points = {-1.0, -a, 0.0, a, 1.0};
      r.weights = {0.1, 49.0 / 90.0, 32.0 / 45.0, 49.0 / 90.0, 0.1};
      break;
    }
    case 6: {
      const Real a = std::sqrt(1.0 / 3.0 - 2.0 * std::sqrt(7.0) / 21.0), b = std::sqrt(1.0 / 3.0 + 2.0 * std::sqrt(7.0) / 21.0);
      const Real wa = (14.0 + std::sqrt(7.0)) / 30.0, wb = (14.0 - std::sqrt(7.0)) / 30.0;
      r.points = {-1.0, -b, -a, a, b, 1.0};
      r.weights = {1.0 / 15.0, wb, wa, wa, wb, 1.0 / 15.0};
      break;
    }
    case 7: {
      const Real s = 2.0 * std::sqrt(5.0 / 3.0) / 11.0;
      const Real a = std::sqrt(5.0 / 11.0 - s), b = std::sqrt(5.0 / 11.0 + s);
      const Real wa = (124.0 + 7.0 * std::sqrt(15.0)) / 350.0, wb = (124.0 - 7.0 * std::sqrt(15.0)) / 350.0;
      r.points = {-1.0, -b, -a, 0.0, a, b, 1.0};
      r.weights = {1.0 / 21.0, wb, wa, 256.0 / 525.0, wa, wb, 1.0 / 21.0};
      break;
    }
    default: throw std::invalid_argument("Lobatto rule: 1 to 7 points through the thickness");
  }
  return r;
}

BelytschkoTsayShell::BelytschkoTsayShell(const ShellSection& section, const material::ShellMaterial& material)
    : section_(section),
      material_(material),
      young_(material.young_modulus()),
      poisson_(material.poisson_ratio()),
      shear_(material.shear_modulus()),
      plane_stress_(material::LinearElastic{young_, poisson_}.plane_stress_modulus()),
      stress_limit_(material.stress_limit()),
      plastic_(material.is_plastic()),
      rule_(ThroughThicknessRule::lobatto(section.thickness_points > 0
                                              ? section.thickness_points
                                              : ShellSection::default_thickness_points(material.is_plastic()))) {}

bool BelytschkoTsayShell::corotational_frame(const NodeMatrix& x, Mat3& rotation) {
  // e3 along r31 x r42, e1 along r21 less its e3 part, e2 = e3 x e1. The e3 part is taken out with the
  // unnormalised normal (r21 - (r21 . n / n . n) n), so that the two square roots are independent and
  // overlap instead of forming one long dependency chain at the start of every element update
  const Vec3 r31 = x.col(2) - x.col(0), r42 = x.col(3) - x.col(1), r21 = x.col(1) - x.col(0);
  const Vec3 n = r31.cross(r42);
  const Real nn = n.squaredNorm();
  const Real scale = std::max(r31.squaredNorm(), r42.squaredNorm());
  if (!(nn > 1e-24 * scale * scale) || !std::isfinite(nn)) return false;
  const Vec3 t = r21 - (r21.dot(n) / nn) * n;
  const Real tt = t.squaredNorm();
  if (!(tt > 1e-24 * scale)) return false;
  const Vec3 e3 = n / std::sqrt(nn), e1 = t / std::sqrt(tt);
  const Vec3 e2 = e3.cross(e1);
  rotation.row(0) = e1.transpose();
  rotation.row(1) = e2.transpose();
  rotation.row(2) = e3.transpose();
  return true;
}

Real BelytschkoTsayShell::stable_time_step(const NodeMatrix& x) const {
  Mat3 R;
  if (!corotational_frame(x, R)) return 0.0;
  const Vec3 centre = x.rowwise().mean();
  const NodeMatrix xl = R * (x.colwise() - centre);
  const Real area2 = (xl(0, 2) - xl(0, 0)) * (xl(1, 3) - xl(1, 1)) + (xl(0, 1) - xl(0, 3)) * (xl(1, 2) - xl(1, 0));
  const Real longest = std::max((x.col(2) - x.col(0)).norm(), (x.col(3) - x.col(1)).norm());
  if (!(area2 > 0) || longest <= 0) return 0.0;
  return stable_time_step(0.5 * area2 / longest);
}

Real BelytschkoTsayShell::stable_time_step(Real characteristic_length) const {
  // coefficient springs add about r of the membrane stiffness; the physical hourglass stiffness
  // stays below the constant-strain modes' (largest eigenvalue of the element unchanged), so no factor
  Real r_mem = 0.0;
  if (section_.hourglass_model == HourglassModel::coefficients)
    r_mem = section_.hourglass_membrane >= 0.0 ? section_.hourglass_membrane : section_.hourglass;
  const Real c = material_.plate_wave_speed() * std::sqrt(1.0 + r_mem);
  return characteristic_length / c;
}

ShellResultants BelytschkoTsayShell::resultants(const Real* stress, Real thickness) const {
  ShellResultants r;
  const int nq = thickness_points(), stride = point_stride();
  for (int q = 0; q < nq; ++q) {
    const Real w = rule_.weights[static_cast<std::size_t>(q)] * 0.5 * thickness;
    const Real z = rule_.points[static_cast<std::size_t>(q)] * 0.5 * thickness;
    const Real* s = stress + stride * q;
    r.nxx += w * s[0];
    r.nyy += w * s[1];
    r.nxy += w * s[2];
    r.qyz += w * s[3] * section_.shear_factor;
    r.qxz += w * s[4] * section_.shear_factor;
    r.mxx += w * z * s[0];
    r.myy += w * z * s[1];
    r.mxy += w * z * s[2];
  }
  return r;
}

ShellElementResult BelytschkoTsayShell::update(const NodeMatrix& x, const NodeMatrix& v, const NodeMatrix& omega, Real dt,
                                               Real* stress, Real* hourglass, Real& thickness) const {
  ShellElementResult out;
  const auto mark_invalid = [&out] {
    out.valid = false;
    out.force.setZero();
    out.moment.setZero();
  };
  Mat3 R;
  if (!corotational_frame(x, R)) {
    mark_invalid();
    return out;
  }
  // local coordinates (origin at the centroid), velocities, angular velocities (eq (17))
  const Vec3 centre = x.rowwise().mean();
  const NodeMatrix xl = R * (x.colwise() - centre);
  NodeMotion vw;
  vw.topRows<3>() = R * v;
  vw.bottomRows<3>() = R * omega;
  auto vl = vw.topRows<3>();
  const auto wl = vw.bottomRows<3>();
  const Row4 xh = xl.row(0), yh = xl.row(1), zh = xl.row(2);

  const Real area2 = (xh(2) - xh(0)) * (yh(3) - yh(1)) + (xh(1) - xh(3)) * (yh(2) - yh(0));
  if (!(area2 > 0.0) || !std::isfinite(area2)) {
    mark_invalid();
    return out;
  }
  const Real area = 0.5 * area2;
  out.area = area;
  const Real longest = std::max((x.col(2) - x.col(0)).norm(), (x.col(3) - x.col(1)).norm());
  out.characteristic_length = area / longest;
  Row4 b1, b2;  // dN/dx, dN/dy at the centre (eq (20))
  b1 << yh(1) - yh(3), yh(2) - yh(0), yh(3) - yh(1), yh(0) - yh(2);
  b2 << xh(3) - xh(1), xh(0) - xh(2), xh(1) - xh(3), xh(2) - xh(0);
  b1 /= area2;
  b2 /= area2;

  // warping correction: remove the in-plane velocities a rigid rotation about e1, e2 gives warped nodes
  const bool warped = section_.warping_correction && zh.cwiseAbs().maxCoeff() > 1e-12 * std::sqrt(area);
  if (warped) {
    const Real rot_x = b2.dot(vl.row(2));   // omega_x of the rigid part: dvz/dy
    const Real rot_y = -b1.dot(vl.row(2));  // omega_y: -dvz/dx
    vl.row(0) -= rot_y * zh;
    vl.row(1) += rot_x * zh;
  }
  const Row4 vx = vl.row(0), vy = vl.row(1), vz = vl.row(2), tx = wl.row(0), ty = wl.row(1);

  // membrane, curvature and transverse shear rates (eqs (21)-(24))
  const Real dx = b1.dot(vx), dy = b2.dot(vy), dxy2 = b2.dot(vx) + b1.dot(vy);
  const Real kx = b1.dot(ty), ky = -b2.dot(tx), kxy2 = b2.dot(ty) - b1.dot(tx);
  // transverse shear: the seed's one-point rates (coefficient model), or the MITC4 assumed covariant shears
  // at the centre (physical model), which leave a Kirchhoff field free on any quadrilateral: the one-point
  // gradient of a quadratic w on a trapezoid misses it by (taper x skew) terms, which locked bending
  const bool physical = section_.hourglass_model == HourglassModel::physical;
  const EdgeShears edges = physical ? edge_shears(xh, yh, zh, corner_normals(xh, yh, zh)) : EdgeShears{};
  const Eigen::Matrix<Real, 2, 2> jacobian = physical ? centre_jacobian(xh, yh) : Eigen::Matrix<Real, 2, 2>::Zero();
  const Eigen::Matrix<Real, 2, 2> jacobian_inverse = physical ? jacobian.inverse() : jacobian;  // (once, for both uses)
  std::array<RateRows, 2> shear_rows;
  if (physical) {
    shear_rows = centre_shear(edges, jacobian_inverse);
    // the rows act on the raw velocities; with the warping correction v_x, v_y carry + (b . v_z) z
    if (warped)
      for (RateRows& r : shear_rows) r.vz() -= r.vx().dot(zh) * b1 + r.vy().dot(zh) * b2;
  }
  const Real dxz2 = physical ? shear_rows[0].rate(vw) : b1.dot(vz) + 0.25 * ty.sum();
  const Real dyz2 = physical ? shear_rows[1].rate(vw) : b2.dot(vz) - 0.25 * tx.sum();

  // stress update through the thickness and resultants (eqs (27)-(29))
  const Real h = thickness;
  const int nq = thickness_points(), stride = point_stride();  // (one virtual call per element)
  Real nxx = 0, nyy = 0, nxy = 0, mxx = 0, myy = 0, mxy = 0, qxz = 0, qyz = 0;
  Real power = 0.0, dzz_mean = 0.0;
  // plastic materials: how much of an elastic stress increment the material took at each point
  // (|d sigma| / |d sigma_trial|), averaged over the section for the membrane and z^2-weighted for bending
  const bool plastic = plastic_;
  const Real nu = poisson_, Gm = shear_, Ep = plane_stress_;
  Real tangent_membrane = 0.0, tangent_bending = 0.0, weight_membrane = 0.0, weight_bending = 0.0;
  // plastic materials: the points' margins to yield (z^2-weighted section mean) and H / (E + H) (section mean)
  Real margin_bending = 0.0, hardening_share = 0.0;
  const Real k = section_.shear_factor;
  // the rates and the stresses before the update at every point, then the section in one material call
  constexpr int kMostPoints = 7;  // (ThroughThicknessRule::lobatto)
  Real rates[kMostPoints][material::kStressComponents], old[kMostPoints][material::kStressComponents], dzz[kMostPoints];
  for (int q = 0; q < nq; ++q) {
    const Real z = rule_.points[static_cast<std::size_t>(q)] * 0.5 * h;
    const Real rate[material::kStressComponents] = {dx + z * kx, dy + z * ky, dxy2 + z * kxy2, dyz2, dxz2};
    std::copy(rate, rate + material::kStressComponents, rates[q]);
    std::copy(stress + stride * q, stress + stride * q + material::kStressComponents, old[q]);
  }
  material_.update_section(stress, stride, rates[0], nq, dt, dzz);
  for (int q = 0; q < nq; ++q) {
    const Real w = rule_.weights[static_cast<std::size_t>(q)] * 0.5 * h;
    const Real z = rule_.points[static_cast<std::size_t>(q)] * 0.5 * h;
    const Real* rate = rates[q];
    const Real* s = stress + stride * q;
    const Real* was = old[q];
    dzz_mean += 0.5 * rule_.weights[static_cast<std::size_t>(q)] * dzz[q];
    if (plastic) {
      const Real t0 = Ep * (rate[0] + nu * rate[1]) * dt, t1 = Ep * (rate[1] + nu * rate[0]) * dt, t2 = Gm * rate[2] * dt;
      const Real trial = t0 * t0 + t1 * t1 + 2.0 * t2 * t2;
      const Real d0 = s[0] - was[0], d1 = s[1] - was[1], d2 = s[2] - was[2];
      const Real ratio = trial > 0.0 ? std::min(1.0, std::sqrt((d0 * d0 + d1 * d1 + 2.0 * d2 * d2) / trial)) : 1.0;
      tangent_membrane += w * ratio;
      weight_membrane += w;
      tangent_bending += w * z * z * ratio;
      weight_bending += w * z * z;
      margin_bending += w * z * z * std::max(0.0, material_.yield_margin(s));
      hardening_share += w * material_.hardening_share(s);
    }
    power += w * (0.5 * (was[0] + s[0]) * rate[0] + 0.5 * (was[1] + s[1]) * rate[1] + 0.5 * (was[2] + s[2]) * rate[2] +
                  k * 0.5 * (was[3] + s[3]) * rate[3] + k * 0.5 * (was[4] + s[4]) * rate[4]);
    nxx += w * s[0];
    nyy += w * s[1];
    nxy += w * s[2];
    qyz += w * k * s[3];
    qxz += w * k * s[4];
    mxx += w * z * s[0];
    myy += w * z * s[1];
    mxy += w * z * s[2];
  }
  out.internal_power = power * area;

  // nodal forces and moments: power conjugates of the rates (eqs (25)-(26))
  NodeMotion fm;
  auto fl = fm.topRows<3>();
  auto ml = fm.bottomRows<3>();
  fl.row(0) = area * (b1 * nxx + b2 * nxy);
  fl.row(1) = area * (b2 * nyy + b1 * nxy);
  ml.row(0) = area * (-b2 * myy - b1 * mxy);
  ml.row(1) = area * (b1 * mxx + b2 * mxy);
  ml.row(2).setZero();
  if (physical) {
    fl.row(2).setZero();
    shear_rows[0].add_force(area * qxz, fm);
    shear_rows[1].add_force(area * qyz, fm);
  } else {
    fl.row(2) = area * (b1 * qxz + b2 * qyz);
    ml.row(0) -= Row4::Constant(0.25 * area * qyz);
    ml.row(1) += Row4::Constant(0.25 * area * qxz);
  }

  // hourglass resistance: physical stabilisation (default) or the seed's coefficient springs
  if (weight_membrane > 0) hardening_share /= weight_membrane;
  const HourglassRates hg = physical
                                ? physical_hourglass(xh, yh, zh, edges, jacobian, jacobian_inverse, warped, b1, b2, h, area,
                                                     weight_membrane > 0 ? tangent_membrane / weight_membrane : 1.0,
                                                     weight_bending > 0 ? tangent_bending / weight_bending : 1.0,
                                                     weight_bending > 0 ? margin_bending / weight_bending : INFINITY)
                                : coefficient_hourglass(xh, yh, b1, b2, h, area);
  // Plastic materials, bending modes: the mode is the variation of the curvature across the element, which the
  // centre's section does not see; at the element's edges the moment is the centre's plus the mode's. So the
  // mode's moment Q_i is bounded by the section's own margin to yield around a held part H_i (state after the
  // resultants): elastic within the margin, beyond it the material's hardening share H / (E + H) of the excess
  // goes into H_i (a one-dimensional elastoplastic law with linear kinematic hardening). A section flowing at the
  // centre (folds, plastic hinges) then carries no spurious moment gradient (perfect plasticity), and a hardening
  // one carries its hardening. The membrane modes keep the first-yield bound alone: the translations pass through
  // the background grid, whose transfer noise their stiffness must keep damping while the section flows (the
  // same margin on them drifted the plastic strip's explicit path by 0.7 %, against 0.36 % without; its Newton
  // path, solved on the shell nodes without the grid, was unchanged).
  Real* held = hourglass + kHourglassModes;  // H_0, H_1
  Real hg_power = 0.0;
  for (int i = 0; i < kHourglassModes; ++i) {
    const RateRows& rows = hg.rows[static_cast<std::size_t>(i)];
    const int only = hg.only_row[static_cast<std::size_t>(i)];  // >= 0: the mode reads that row of vw alone
    const Real rate = only >= 0 ? rows.m.row(only).dot(vw.row(only)) : rows.rate(vw);
    if (hg.stiffness[i] == 0.0 && hourglass[i] == 0.0) continue;  // (a held resultant still acts)
    const Real old = hourglass[i];
    const Real trial = old + dt * hg.stiffness[i] * rate;
    const Real excess = i < 2 ? std::abs(trial - held[i]) - hg.margin[i] : -1.0;  // (margin infinite if elastic)
    if (excess > 0.0) {
      const Real sign = trial > held[i] ? 1.0 : -1.0;
      held[i] = std::clamp(held[i] + sign * hardening_share * excess, -hg.limit[i], hg.limit[i]);
      hourglass[i] = std::clamp(trial - sign * (1.0 - hardening_share) * excess, -hg.limit[i], hg.limit[i]);
    } else {
      hourglass[i] = std::clamp(trial, -hg.limit[i], hg.limit[i]);
    }
    hg_power += 0.5 * (old + hourglass[i]) * rate;
    if (only >= 0)
      fm.row(only) += hourglass[i] * rows.m.row(only);
    else
      rows.add_force(hourglass[i], fm);
  }
  out.hourglass_power = hg_power;

  // transpose of the warping projection: in-plane forces at warped nodes feed the transverse forces
  if (warped) {
    const Real sx = fl.row(0).dot(zh), sy = fl.row(1).dot(zh);
    fl.row(2) += -sx * (-b1) + sy * b2;  // d(v_x)/d(vz_J) = -z_I * (-b1_J), d(v_y)/d(vz_J) = z_I * b2_J
  }

  // thickness update (plane stress)
  thickness = h * (1.0 + dt * dzz_mean);

  // back to the global frame (eq (37))
  out.force = R.transpose() * fl;
  out.moment = R.transpose() * ml;
  return out;
}

namespace {

/// h = [1, -1, 1, -1] and the Flanagan-Belytschko gamma = h - (h . x) b1 - (h . y) b2 (zero on linear fields).
Eigen::Matrix<Real, 1, 4> hourglass_vector() { return (Eigen::Matrix<Real, 1, 4>() << 1.0, -1.0, 1.0, -1.0).finished(); }
Eigen::Matrix<Real, 1, 4> hourglass_gamma(const Eigen::Matrix<Real, 1, 4>& xh, const Eigen::Matrix<Real, 1, 4>& yh,
                                          const Eigen::Matrix<Real, 1, 4>& b1, const Eigen::Matrix<Real, 1, 4>& b2) {
  const Eigen::Matrix<Real, 1, 4> hv = hourglass_vector();
  return hv - hv.dot(xh) * b1 - hv.dot(yh) * b2;
}

}  // namespace

BelytschkoTsayShell::CornerNormals BelytschkoTsayShell::corner_normals(const Row4& xh, const Row4& yh, const Row4& zh) {
  // x(xi, eta) = c + xi a + eta b + xi eta g with a = sum xi_J x_J / 4, b = sum eta_J x_J / 4,
  // g = sum xi_J eta_J x_J / 4; at corner k, x_,xi = a + eta_k g and x_,eta = b + xi_k g
  const Real xi[4] = {-1.0, 1.0, 1.0, -1.0}, eta[4] = {-1.0, -1.0, 1.0, 1.0};
  const Row4 rxi = (Row4() << -0.25, 0.25, 0.25, -0.25).finished(), reta = (Row4() << -0.25, -0.25, 0.25, 0.25).finished();
  const Row4 rg = (Row4() << 0.25, -0.25, 0.25, -0.25).finished();
  const Vec3 a(rxi.dot(xh), rxi.dot(yh), rxi.dot(zh)), b(reta.dot(xh), reta.dot(yh), reta.dot(zh));
  const Vec3 g(rg.dot(xh), rg.dot(yh), rg.dot(zh));
  CornerNormals n;
  for (int k = 0; k < 4; ++k) n.col(k) = (a + eta[k] * g).cross(b + xi[k] * g);
  const Row4 inverse_length = n.colwise().squaredNorm().cwiseSqrt().cwiseInverse();  // (four at once)
  return n * inverse_length.asDiagonal();
}

BelytschkoTsayShell::EdgeShears BelytschkoTsayShell::edge_shears(const Row4& xh, const Row4& yh, const Row4& zh,
                                                                  const CornerNormals& n) {
  constexpr int ends[4][2] = {{0, 1}, {3, 2}, {0, 3}, {1, 2}};  // edges along xi (0-1, 3-2), then along eta
  EdgeShears out;
  for (int e = 0; e < 4; ++e) {
    const int i = ends[e][0], j = ends[e][1];
    NodeMotion& g = e < 2 ? out.xi.m : out.eta.m;
    const Vec3 d = 0.5 * (n.col(i) + n.col(j));
    const Vec3 edge(xh(j) - xh(i), yh(j) - yh(i), zh(j) - zh(i));
    g.col(j).head<3>() = 0.5 * d;
    g.col(i).head<3>() = -0.5 * d;
    for (int k : {i, j}) g.col(k).tail<3>() = 0.25 * n.col(k).cross(edge);  // E . (theta x n) = theta . (n x E)
  }
  return out;
}

Eigen::Matrix<Real, 2, 2> BelytschkoTsayShell::centre_jacobian(const Row4& xh, const Row4& yh) {
  const Row4 xi = (Row4() << -1.0, 1.0, 1.0, -1.0).finished(), eta = (Row4() << -1.0, -1.0, 1.0, 1.0).finished();
  Eigen::Matrix<Real, 2, 2> jac;
  jac << 0.25 * xi.dot(xh), 0.25 * xi.dot(yh), 0.25 * eta.dot(xh), 0.25 * eta.dot(yh);
  return jac;
}

std::array<BelytschkoTsayShell::RateRows, 2> BelytschkoTsayShell::centre_shear(
    const EdgeShears& edges, const Eigen::Matrix<Real, 2, 2>& jinv) {
  // covariant shears at the centre: gamma_xi = (g_01 + g_32) / 2, gamma_eta = (g_03 + g_12) / 2; Cartesian
  // (gamma_x, gamma_y) = J^-1 (gamma_xi, gamma_eta), J's rows g_xi, g_eta at the centre
  std::array<RateRows, 2> out;
  for (int c = 0; c < 2; ++c)
    out[static_cast<std::size_t>(c)].m = 0.5 * jinv(c, 0) * edges.xi.m + 0.5 * jinv(c, 1) * edges.eta.m;
  return out;
}

BelytschkoTsayShell::HourglassRates BelytschkoTsayShell::coefficient_hourglass(const Row4& xh, const Row4& yh,
                                                                               const Row4& b1, const Row4& b2, Real h,
                                                                               Real area) const {
  // Belytschko-Tsay 1983 springs with the Flanagan-Belytschko gamma vectors (seed eqs (30)-(36))
  HourglassRates out;
  for (RateRows& r : out.rows) r = RateRows::zero();
  const Real r = section_.hourglass;
  const Real r_bend = section_.hourglass_bending >= 0.0 ? section_.hourglass_bending : r;
  const Real r_mem = section_.hourglass_membrane >= 0.0 ? section_.hourglass_membrane : r;
  const Real r_w = section_.hourglass_transverse >= 0.0 ? section_.hourglass_transverse : r;
  const Row4 hv = hourglass_vector();
  const Row4 gamma = hourglass_gamma(xh, yh, b1, b2);
  const Real bsq = b1.squaredNorm() + b2.squaredNorm();
  const Real E = young_, G = shear_, k = section_.shear_factor;
  const Real c_bend = r_bend * E * h * h * h * area / 192.0 * bsq;
  const Real c_w = r_w * k * G * h * h * h / 12.0 * bsq;
  const Real c_mem = r_mem * E * h * area / 8.0 * bsq;
  // transverse mode: q_w = gamma . v_z + cx . theta_x + cy . theta_y (cx = cy = 0 in the standard form)
  Row4 cx = Row4::Zero(), cy = Row4::Zero();
  if (section_.kirchhoff_transverse_hourglass) {
    // -1/2 of the rotation part of sum_e s_e L_e gamma_e over the edges e = (I, J), s_e = +1, -1, +1, -1,
    // less its value for a constant rotation (removed with the mean rotation, as gamma removes linear w)
    const Real sign[4] = {1.0, -1.0, 1.0, -1.0};
    for (int e = 0; e < 4; ++e) {
      const int i = e, j = (e + 1) % 4;
      const Real dxe = xh(j) - xh(i), dye = yh(j) - yh(i);
      cy(i) -= 0.25 * sign[e] * dxe;
      cy(j) -= 0.25 * sign[e] * dxe;
      cx(i) += 0.25 * sign[e] * dye;
      cx(j) += 0.25 * sign[e] * dye;
    }
    cy.array() -= 0.25 * hv.dot(xh);
    cx.array() += 0.25 * hv.dot(yh);
  }
  out.rows[0].tx() = gamma;
  out.rows[1].ty() = gamma;
  out.rows[2].vz() = gamma;
  out.rows[2].tx() = cx;
  out.rows[2].ty() = cy;
  out.rows[3].vx() = gamma;
  out.rows[4].vy() = gamma;
  out.stiffness = {c_bend, c_bend, c_w, c_mem, c_mem, 0.0, 0.0};
  return out;
}

BelytschkoTsayShell::HourglassRates BelytschkoTsayShell::physical_hourglass(const Row4& xh, const Row4& yh, const Row4& zh,
                                                                            const EdgeShears& edges,
                                                                            const Eigen::Matrix<Real, 2, 2>& jacobian,
                                                                            const Eigen::Matrix<Real, 2, 2>& jinv,
                                                                            bool corrected,
                                                                            const Row4& b1, const Row4& b2, Real h,
                                                                            Real area, Real tangent_membrane,
                                                                            Real tangent_bending, Real margin_bending) const {
  HourglassRates out;
  const Row4 gamma = hourglass_gamma(xh, yh, b1, b2);  // gamma . u = 4 q for u = q xi eta
  const Real E = young_, G = shear_, k = section_.shear_factor;
  // bending: energy of the bilinear mode's normal strain alone (the parasitic shear of the bilinear field
  // left out, so pure out-of-plane bending is exact on rectangles):
  // (1/2) E t int (q d(xi eta)/dx)^2 dA = (1/2) (4/3) E t A |b1|^2 q^2 = (1/2) (E t A |b1|^2 / 12) (gamma . u)^2
  const Real bx = b1.squaredNorm(), by = b2.squaredNorm();
  out.rows[0].tx() = gamma;  // theta_x mode: kappa_yy = -d theta_x / dy
  out.rows[1].ty() = gamma;  // theta_y mode: kappa_xx = d theta_y / dx
  out.only_row[0] = 3;       // (the other rows of these two are never read)
  out.only_row[1] = 4;
  const Real bend = E * h * h * h / 12.0 * area / 12.0, mem = E * h * area / 12.0;
  // membrane: the mode u = q xi eta taken along the natural directions g_xi = sum xi_I x_I / 4 and g_eta
  // (centre), with the normal strain along each alone: e_xi = (q . g_xi) eta / |g_xi|^2, so
  // (1/2) E t (A / 3) (q . g_xi)^2 / |g_xi|^4 = (1/2) (E t A / (48 |g_xi|^2)) (t_xi . (gamma . u))^2, t_xi = g_xi / |g_xi|.
  // In-plane bending along xi of any parallelogram stores exactly its bending energy and leaves the eta mode
  // at rest; the Cartesian x / y modes (the same on rectangles) also strained the y mode of a skewed
  // element, 117 x the bending energy on a 5:1 element skewed by 0.2 (MacNeal-Harder's straight beam)
  const Eigen::Vector2d g_xi = jacobian.row(0).transpose(), g_eta = jacobian.row(1).transpose();
  const Real length_xi = g_xi.norm(), length_eta = g_eta.norm();
  const Real mem_xi = 0.5 / length_xi, mem_eta = 0.5 / length_eta;  // play the part of |b1|, |b2|
  const Eigen::Vector2d t_xi = g_xi / length_xi, t_eta = g_eta / length_eta;
  out.rows[3].vx() = t_xi(0) * gamma;
  out.rows[3].vy() = t_xi(1) * gamma;
  out.rows[4].vx() = t_eta(0) * gamma;
  out.rows[4].vy() = t_eta(1) * gamma;
  for (int slot : {3, 4}) out.rows[slot].vz().setZero(), out.rows[slot].tz().setZero();
  // on a warped facet the modes read the in-plane motion of the nodes' projections on the facet, v less the
  // motion of the offset z_I by the node's own rotation (v'_x = v_x - theta_y z_I, v'_y = v_y + theta_x z_I,
  // as the drilling strain below; the rows act on the rigid-rotation corrected velocities, so that
  // correction is taken out through the v_z rows). Read from the nodes themselves, the modes saw the
  // bending rotations times the warp: 2.3 % stiff on the thin twisted beam (12 x 2, out of plane)
  const Row4 gz = gamma.cwiseProduct(zh);
  for (int slot : {3, 4}) {
    const Eigen::Vector2d& t = slot == 3 ? t_xi : t_eta;
    out.rows[slot].ty() = -t(0) * gz;
    out.rows[slot].tx() = t(1) * gz;
    if (corrected) out.rows[slot].vz() -= gz.sum() * (t(0) * b1 + t(1) * b2);
  }
  // transverse shear: the hourglass part of the MITC4 (Bathe-Dvorkin 1985) edge-tied shears. Covariant
  // shear at the midpoint of edge (I, J), with the bilinear surface's normal n_K at each corner as the
  // director: g = [(v_J - v_I) . d + E . (theta_I x n_I + theta_J x n_J) / 2] / 2, d = (n_I + n_J) / 2,
  // E = x_J - x_I (on a flat facet n_K = e3 and g = [(w_J - w_I) + dx theta_y_avg - dy theta_x_avg] / 2).
  // gamma_xi varies linearly in eta between edges 0-1 and 3-2, gamma_eta in xi between 0-3 and 1-2.
  // Their differences D_xi, D_eta carry (1/2) k G t (A / 3) |J^-T e|^2 D^2 of energy: zero for rigid
  // motions and for the Kirchhoff twist w = c x y, on warped facets too (with e3 as every corner's
  // director the twist of a warped facet gave D of order twist x warp, which locked the thin twisted
  // beam); MITC4's shear energy exactly on parallelograms with the centre term below.
  // D_xi = (g_32 - g_01) / 2, D_eta = (g_12 - g_03) / 2: the edge blocks with the first edge's nodes negated
  out.rows[2].m = edges.xi.m * Row4(-0.5, -0.5, 0.5, 0.5).asDiagonal();
  out.rows[5].m = edges.eta.m * Row4(-0.5, 0.5, 0.5, -0.5).asDiagonal();
  // the velocities above are the raw ones: with the warping correction the rows act on the corrected
  // v_x = raw + (b1 . v_z) z, v_y = raw + (b2 . v_z) z, so the correction is taken out through the v_z rows
  if (corrected)
    for (int slot : {2, 5}) out.rows[slot].vz() -= out.rows[slot].vx().dot(zh) * b1 + out.rows[slot].vy().dot(zh) * b2;
  const Real c_xi = jinv.col(0).squaredNorm(), c_eta = jinv.col(1).squaredNorm();
  const Real shear = k * G * h * area / 3.0;
  // drilling: theta_z (mean) - omega_z, omega_z = (b1 . v'_y - b2 . v'_x) / 2 the in-plane spin of the
  // facet. On a warped facet v' are the nodes' velocities less the motion of their offset z_I from the
  // facet by the node's own rotation, v'_x = v_x - theta_y z_I, v'_y = v_y + theta_x z_I (raw velocities;
  // with the warping correction the rows act on the corrected v_x = raw + (b1 . v_z) z,
  // v_y = raw + (b2 . v_z) z), so that a Kirchhoff bending field of the warped surface gives no drilling
  // strain. The rigid-rotation correction alone left one of order curvature x warp, which a stiff
  // penalty turned into locking
  out.rows[6].tx() = -0.5 * b1.cwiseProduct(zh);
  out.rows[6].ty() = -0.5 * b2.cwiseProduct(zh);
  if (corrected)
    out.rows[6].vz() = 0.5 * (b1.dot(zh) * b2 - b2.dot(zh) * b1);
  else
    out.rows[6].vz().setZero();
  out.rows[6].tz() = Row4::Constant(0.25);
  out.rows[6].vy() = -0.5 * b1;
  out.rows[6].vx() = 0.5 * b2;
  // scaled by the material's current tangent ratio (Belytschko-Bindeman: the stabilisation follows the
  // material's response, so it does not stiffen a section that is flowing plastically)
  const Real sm = tangent_membrane, sb = tangent_bending;
  out.stiffness = {bend * by * sb,
                   bend * bx * sb,
                   shear * c_xi * sm,
                   mem * mem_xi * mem_xi * sm,
                   mem * mem_eta * mem_eta * sm,
                   shear * c_eta * sm,
                   section_.drilling * G * h * area};
  // plastic materials: each mode's resultant is bounded where its peak stress (at the element's edge,
  // the outer fibre) reaches the yield stress, so the stabilisation yields with the material instead of
  // stiffening plastic folds: Q = (t A |b| / 6) sigma_peak (membrane), (t^2 A |b| / 36) sigma_peak
  // (bending), (k t A / 3) |J^-T e| tau_peak with tau = sigma_y / sqrt(3) (transverse shear)
  const Real sy = stress_limit_;
  if (std::isfinite(sy)) {
    const Real ax = std::sqrt(bx), ay = std::sqrt(by);
    const Real ty_shear = sy / std::sqrt(3.0);
    // the bending modes' margin: the same peak stress at the section's margin to yield
    out.margin[0] = std::min(sy, margin_bending) * h * h * area * ay / 36.0;
    out.margin[1] = std::min(sy, margin_bending) * h * h * area * ax / 36.0;
    out.limit = {sy * h * h * area * ay / 36.0, sy * h * h * area * ax / 36.0,
                 k * h * area / 3.0 * std::sqrt(c_xi) * ty_shear, sy * h * area * mem_xi / 6.0, sy * h * area * mem_eta / 6.0,
                 k * h * area / 3.0 * std::sqrt(c_eta) * ty_shear, INFINITY};
  }
  return out;
}

}  // namespace lamina::shell
