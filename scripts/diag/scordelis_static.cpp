// Diagnostic: static linear FE solve of the Scordelis-Lo quarter roof with the BT element's tangent
// stiffness built column by column from its internal force (zero initial stress, unit nodal rate, dt = 1:
// f = K u exactly for the linear material). No background grid, no dynamics.
// Build: cmake --build build --target scordelis_static_diagnostic (the library's flags: Eigen's
// fixed-size layout depends on -march); run build/scordelis_static_diagnostic.
// Usage: sstat n_circ n_axial [hourglass hg_bending hg_membrane hg_transverse [p|h]]  (p: flat Navier plate, h: theta_y = 0 on the diaphragm)
// KIRCHHOFF=1 in the environment: transverse_hourglass kirchhoff. hourglass < 0: the physical model (the
// default of the code), DRILL=<factor> its drilling penalty.
#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>
#include "shell/belytschko_tsay_shell.hpp"
using namespace lamina;
using namespace lamina::shell;
int main(int argc, char** argv) {
  const int nc = argc > 1 ? std::atoi(argv[1]) : 6, na = argc > 2 ? std::atoi(argv[2]) : nc;
  const double hg = argc > 3 ? std::atof(argv[3]) : -1.0, hgb = argc > 4 ? std::atof(argv[4]) : -1.0;
  const double hgm = argc > 5 ? std::atof(argv[5]) : -1.0, hgw = argc > 6 ? std::atof(argv[6]) : -1.0;
  const bool plate = argc > 7 && argv[7][0] == 'p';  // square plate 10 x 10, simply supported (soft), quarter
  const bool hard = argc > 7 && argv[7][0] == 'h';   // also theta_y = 0 on the diaphragm
  const double R = 25, L = 25, phi = 40.0 * M_PI / 180.0, t = 0.25, E = 4.32e8, q = 90;
  LinearElasticShellMaterial mat(E, 0.0, 1.0);
  ShellSection sec;
  sec.hourglass = hg;
  sec.hourglass_bending = hgb;
  sec.hourglass_membrane = hgm;
  sec.hourglass_transverse = hgw;
  sec.kirchhoff_transverse_hourglass = std::getenv("KIRCHHOFF") != nullptr;
  sec.hourglass_model = hg < 0 ? HourglassModel::physical : HourglassModel::coefficients;
  if (std::getenv("DRILL")) sec.drilling = std::atof(std::getenv("DRILL"));
  BelytschkoTsayShell el(sec, mat);
  const int nn = (nc + 1) * (na + 1), ndof = 6 * nn;
  std::vector<Vec3> X(nn);
  auto id = [&](int i, int j) { return j * (nc + 1) + i; };  // i circumferential (0 = crown), j axial (0 = diaphragm)
  for (int j = 0; j <= na; ++j)
    for (int i = 0; i <= nc; ++i) {
      const double u = phi * i / nc;
      X[id(i, j)] = plate ? Vec3(5.0 * i / nc, 5.0 * j / na, 0.0) : Vec3(R * std::sin(u), L * j / na, R * std::cos(u));
    }
  static Eigen::MatrixXd K; K = Eigen::MatrixXd::Zero(ndof, ndof);
  Eigen::VectorXd F = Eigen::VectorXd::Zero(ndof);
  for (int j = 0; j < na; ++j)
    for (int i = 0; i < nc; ++i) {
      int nd[4] = {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)};
      NodeMatrix x;
      for (int a = 0; a < 4; ++a) x.col(a) = X[nd[a]];
      // orientation: outward normal (+radial)
      const Vec3 n = (x.col(2) - x.col(0)).cross(x.col(3) - x.col(1));
      if (!plate && n.dot(x.rowwise().mean()) < 0) { std::swap(nd[1], nd[3]); for (int a = 0; a < 4; ++a) x.col(a) = X[nd[a]]; }
      Mat3 Rm;
      BelytschkoTsayShell::corotational_frame(x, Rm);
      const NodeMatrix xl = Rm * (x.colwise() - x.rowwise().mean());
      const double area = 0.5 * ((xl(0, 2) - xl(0, 0)) * (xl(1, 3) - xl(1, 1)) + (xl(0, 1) - xl(0, 3)) * (xl(1, 2) - xl(1, 0)));
      for (int a = 0; a < 4; ++a) F(6 * nd[a] + 2) -= q * area / 4.0;
      for (int c = 0; c < 24; ++c) {
        NodeMatrix v = NodeMatrix::Zero(), w = NodeMatrix::Zero();
        (c % 6 < 3 ? v : w)(c % 3, c / 6) = 1.0;
        std::vector<double> st(el.stress_size(), 0.0);
        double hgs[BelytschkoTsayShell::kHourglassSize] = {}, h = t;
        const ShellElementResult r = el.update(x, v, w, 1.0, st.data(), hgs, h);
        for (int a = 0; a < 4; ++a)
          for (int k = 0; k < 3; ++k) {
            K(6 * nd[a] + k, 6 * nd[c / 6] + c % 6) += r.force(k, a);
            K(6 * nd[a] + 3 + k, 6 * nd[c / 6] + c % 6) += r.moment(k, a);
          }
      }
    }
  std::vector<char> fixed(ndof, 0);
  for (int j = 0; j <= na; ++j)
    for (int i = 0; i <= nc; ++i) {
      const int n = id(i, j);
      if (plate) {
        if (i == 0 || j == 0) fixed[6 * n + 2] = 1;                                  // simply supported (soft)
        if (i == nc) fixed[6 * n + 0] = fixed[6 * n + 4] = 1;                        // x symmetry
        if (j == na) fixed[6 * n + 1] = fixed[6 * n + 3] = 1;                        // y symmetry
        if (i == 0) fixed[6 * n + 1] = 1;
        if (j == 0) fixed[6 * n + 0] = 1;
        fixed[6 * n + 5] = 1;                                                        // drilling (flat plate)
        continue;
      }
      if (j == 0) fixed[6 * n + 0] = fixed[6 * n + 2] = 1;                          // diaphragm u_x = u_z = 0
      if (j == 0 && hard) fixed[6 * n + 4] = 1;                                  // and theta_y = 0 (MacNeal-Harder)
      if (j == na) fixed[6 * n + 1] = fixed[6 * n + 3] = fixed[6 * n + 5] = 1;      // y symmetry
      if (i == 0) fixed[6 * n + 0] = fixed[6 * n + 4] = fixed[6 * n + 5] = 1;       // x symmetry
    }
  const double sym = (K - K.transpose()).norm() / K.norm();
  std::vector<int> fr;
  for (int d = 0; d < ndof; ++d) if (!fixed[d]) fr.push_back(d);
  Eigen::MatrixXd Kf(fr.size(), fr.size());
  Eigen::VectorXd Ff(fr.size());
  for (size_t a = 0; a < fr.size(); ++a) { Ff(a) = F(fr[a]); for (size_t b = 0; b < fr.size(); ++b) Kf(a, b) = K(fr[a], fr[b]); }
  // tiny drilling regularisation: singular drilling modes of nodes whose elements are coplanar
  const double kd = (std::getenv("KDRILL") ? std::atof(std::getenv("KDRILL")) : 1e-9) * Kf.diagonal().maxCoeff();
  Eigen::MatrixXd Kr = Kf + kd * Eigen::MatrixXd::Identity(fr.size(), fr.size());
  Eigen::VectorXd uf = Kr.ldlt().solve(Ff);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(ndof);
  for (size_t a = 0; a < fr.size(); ++a) u(fr[a]) = uf(a);
  const double uz = u(6 * id(nc, na) + 2);
  if (plate) {  // Navier: w_centre = 0.00406235 q a^4 / D, a = 10, t = 0.25, nu = 0
    const double D = E * t * t * t / 12.0, ref = 0.00406235 * q * 1e4 / D;
    std::printf("plate %dx%d: w_centre %.6e ratio %.4f\n", nc, na, uz, -uz / ref);
    return 0;
  }
  std::printf("mesh %dx%d hg %.3g hgb %.3g hgm %.3g hgw %.3g: asym %.2e  uz_edge %.6f  ratio %.4f  residual %.2e\n", nc, na, hg, hgb, hgm, hgw, sym, uz, -uz / 0.3024,
              (Kf * uf - Ff).norm() / Ff.norm());
}
