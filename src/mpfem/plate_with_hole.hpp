#pragma once
// 2D particle generator for the quarter plate with a circular hole (Kirsch problem; used by the
// mpfem validation; particles for seed 001's particle quadrature eqs 4-6): a mapped grid on a rectangle.
//
// The quarter [x0, x0 + width] x [y0, y0 + height] with a hole of `radius` centred at (x0, y0).
// Particle (i, j), i = 0..n_radial-1 from the hole outwards, j = 0..n_angular-1 from angle 0
// (the y = y0 edge) to 90 degrees (the x = x0 edge): on the ray at angle theta_j = (pi/2) j /
// (n_angular - 1) between the hole point and the point where the ray leaves the rectangle, at
// the fraction s_i^grading (s_i = i / (n_radial - 1); grading > 1 packs particles at the hole).
// An odd n_angular on a square puts a particle on the outer corner.
// Sets: hole (i = 0), outer (i = last), ymin (j = 0), xmin (j = last), and xmax / ymax (outer
// particles on those edges).
#include <map>
#include <string>

#include "mpfem/particle_elements.hpp"

namespace lamina::mpfem {

struct PlateWithHoleSpec {
  Vec2 origin = Vec2::Zero();  // hole centre = corner of the quarter model
  Real width = 5, height = 5;
  Real radius = 1;
  int n_radial = 17, n_angular = 17;
  Real grading = 1.0;
};

struct GeneratedParticles {
  ParticleLayout layout;
  Eigen::VectorXd area;                      // tributary areas (mapped-cell quarters), sum = body area to O(h^2)
  std::map<std::string, IndexList> sets;
};

/// Throws InputError (key "mpfem.hole") for impossible parameters.
GeneratedParticles generate_plate_with_hole(const PlateWithHoleSpec& spec);

}  // namespace lamina::mpfem
