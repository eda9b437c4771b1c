#pragma once
// Mirror columns across the supported straight edges of a plate lattice (docs/pd.md, "Supported edges:
// mirror columns"): the in-plane families of the director plate model reach past a clamp, a simple
// support or a symmetry plane into mirror images of the columns inside it, so that the gradient fits
// next to a supported edge are two-sided, as in the interior (free edges keep one-sided families).
//
// A straight outer column line (the lowest or highest x or y of the column centres) is mirrored when
// every node of every column on it holds (fixed or prescribed) the edge-normal in-plane displacement
// - a clamp (z held too) or a symmetry plane: w continues evenly - or else the z displacement - a simple
// support: w continues oddly. With n the edge normal and t its tangent, the mid-surface m and the
// director a of the columns continue as
//   even w (normal held):  m_n odd, m_z even, a_n odd, a_t even, a_z even, m_t odd if held, else even;
//   odd w (z held):        m_n odd, m_t odd, m_z odd, a_n even, a_t odd, a_z even;
// "odd" about the edge column's value (a linear field continues linearly). A mirror column G of column J
// (E: the edge column at J's tangential position) moves as m_G = S_m m_J + (I - S_m) m_E and
// a_G = S_a a_J + (I - S_a) a_E: a fixed linear combination of real columns (corners: mirrors of
// mirrors). Mirror columns carry no energy of their own. A column on a mirror line carries half its
// energy (the half of its cell beyond the line is the mirrored half; a quarter at a corner). Where the
// tangential motion is free, that half-cell strip still carries the stress along the edge, as the
// lattice's cell does (a bar: `strip`), so that a load spread over the lattice's width stays uniform.
#include <string>
#include <utility>
#include <vector>

#include "core/types.hpp"
#include "pd/plate_columns.hpp"

namespace lamina::pd {

/// One term of a mirror column's motion: the real column and the diagonals of the 3 x 3 factors of its
/// mid-surface m and director a.
struct MirrorTerm {
  Index column = 0;
  Vec3 m = Vec3::Ones(), a = Vec3::Ones();
};

struct PlateEdgeMirror {
  PointMatrix centre;                            // 3 x G: in-plane centres of the mirror columns (z = 0)
  std::vector<Index> image_of;                   // per mirror column: the column (real or mirror) it reflects
  std::vector<std::vector<MirrorTerm>> motion;   // per mirror column: m_G = sum_terms m o m_column (a alike)
  Eigen::VectorXd energy_factor;                 // per real column: 1, 1/2 on a mirror line, 1/4 at a corner
  // per real column (2 x C): the half-cell strip beyond a mirror line whose tangential motion t is free
  // adds 1/2 E E_tt^2 per energy-weighted volume of the column, times strip(t, c) (1 on such a line)
  Eigen::Matrix2Xd strip;
  std::vector<std::string> edges;                // the mirrored edges, e.g. "x = 0 (clamped or symmetry)"
  Index count() const { return static_cast<Index>(image_of.size()); }
};

/// No mirror: every energy factor 1, no strip.
PlateEdgeMirror no_edge_mirror(Index columns);

/// The mirror columns of every supported outer edge of the columns with in-plane centres `centre`
/// (3 x C), reaching `reach` past the edge. held: per node dof (3 per node), whether it is fixed or
/// prescribed. Edges whose mirror positions do not fall on the lattice (an irregular edge) are left as
/// they are.
PlateEdgeMirror mirror_supported_edges(const PlateColumns& columns, const PointMatrix& centre,
                                       const std::vector<char>& held, Real reach);

}  // namespace lamina::pd
