#pragma once
// Volume part of the Galerkin EFG system: K = sum_q B^T D B w_q over the background quadrature,
// f = sum_q N^T b w_q (body force per unit volume).
//
// Isotropic elasticity per node pair (I, J) and components (a, b):
//   K_IJ(a, b) = sum_q w_q [ lambda phi_I,a phi_J,b + mu phi_I,b phi_J,a + mu delta_ab grad phi_I . grad phi_J ],
// evaluated per background cell with dense products S_ab = X_a^T diag(w) X_b, X_a(q, i) = phi_i,a(x_q)
// over the cell's neighbour nodes (the union of the neighbours of its quadrature points).
//
// Parallel and deterministic: the cells are split into one contiguous chunk per thread (the same
// split for the same thread count), and each chunk into two halves. All threads assemble their first
// halves, then (after a barrier) their second halves. When the value ranges of the halves assembled
// at the same time do not overlap (cells ordered along the body and chunks wider than the supports,
// the usual case) every thread adds straight into the matrix: no copies, and every value receives its
// terms in a fixed order. Otherwise each thread adds into its own copy of the range it touches and
// the copies are summed in thread order. With a different thread count only the summation order of a
// few terms changes (differences at the 1e-16 relative level).
//
// Selective reduced integration (efg.integration.volumetric: reduced): the lambda term
// lambda div u div v is integrated with a lower-order Gauss rule on the same cells (default order
// gauss - 1 per direction, at least 1), the mu term with the full rule. This removes volumetric
// locking for nearly incompressible materials (nu -> 0.5, lambda -> infinity): the number of
// incompressibility constraints drops below the number of unknowns. The mu term keeps the
// stiffness stable (no spurious zero-energy modes).
//
// Variationally consistent integration (VCI, Chen, Hillman & Rueter, IJNME 95 (2013) 387-418):
// Gauss quadrature of rational MLS functions violates the integration constraint
//   sum_q grad phi_I(x_q) w_q = sum_s phi_I(x_s) n_s w_s   (discrete divergence theorem),
// so the linear patch test holds only to the quadrature error. With correction `vci` the test
// function gradients are replaced by grad phi_I + xi_I phi_I, with the constant vector
//   xi_I = (sum_s phi_I n w_s - sum_q grad phi_I w_q) / sum_q phi_I w_q,
// which restores the constraint exactly (Petrov-Galerkin: K is no longer symmetric, so the
// system is solved by sparse LU). The trial functions are unchanged.
//
// Gradient smoothing over the background cells (correction `smoothed`; quadratically consistent
// smoothed gradients in the spirit of Duan, Li & Belytschko, IJNME 92 (2012) 399-424, and Wang & Wu,
// CMAME 349 (2019) 628-672): in each cell C the gradient of phi_I is replaced by the linear field
// g_I(x) = G_I q(x), q = [1, (x - x_C) / s], that satisfies the divergence theorem against every
// linear q on the cell's own quadrature,
//   sum_q w_q g_I(x_q) q_k(x_q) = sum_f w_f n_f phi_I(x_f) q_k(x_f) - sum_q w_q phi_I(x_q) grad q_k,
// f over the points of the cell's six faces. So g_I is the L2 projection of grad phi_I onto linear
// fields, exact wherever phi_I is a polynomial of degree <= 2; for a field u of the basis the
// smoothed gradient is exact (MLS reproduces u), and the interior face sums cancel between cells,
// so the quadratic patch test holds to round-off whatever the node layout, the cell shape or the
// misalignment of supports and cells. Trial and test gradients are the same: K stays symmetric.
#include <utility>
#include <vector>

#include "efg/background_quadrature.hpp"
#include "material/linear_elastic.hpp"
#include "mls/mls_shape_functions.hpp"
#include "solve/block_pattern.hpp"

namespace lamina::efg {

struct VolumeIntegrals {
  Eigen::Matrix3Xd gradient;  // sum_q grad phi_I w_q   (3 x N)
  Eigen::VectorXd value;      // sum_q phi_I w_q        (N)
};

/// Pass 1: the sorted union of the MLS neighbours of each cell's quadrature points; with
/// `integrals` also the volume integrals of phi_I and grad phi_I (for VCI); with `point_groups` the
/// distinct neighbour lists of the points (appended, cell by cell): two nodes couple in K only if
/// some quadrature point sees both, which is sparser than the cell unions.
/// With `faces` the neighbours of each cell's face points join its union (gradient smoothing), found with the
/// singular remedy if `grow_at_faces` (as assemble_volume evaluates them).
std::vector<IndexList> cell_neighbours(const mls::MlsShapeFunctions& shapes, const VolumeQuadrature& quadrature,
                                       VolumeIntegrals* integrals, std::vector<IndexList>* point_groups = nullptr,
                                       const CellFaceQuadrature* faces = nullptr, bool grow_at_faces = false);

/// VCI correction xi_I (3 x N) from the volume integrals and the boundary integrals sum_s phi_I n w_s.
Eigen::Matrix3Xd vci_correction(const VolumeIntegrals& volume, const Eigen::Matrix3Xd& boundary);

struct VolumeAssembly {
  const mls::MlsShapeFunctions* shapes = nullptr;
  const VolumeQuadrature* quadrature = nullptr;
  const std::vector<IndexList>* cell_nodes = nullptr;
  const std::vector<int>* material_of_point = nullptr;            // index into materials
  const std::vector<material::LinearElastic>* materials = nullptr;
  const Eigen::Matrix3Xd* body_force = nullptr;                   // 3 x Q force per unit volume (optional)
  const Eigen::Matrix3Xd* vci = nullptr;                          // 3 x N xi_I (optional; needs a full pattern)
  /// Selective reduced integration: the lambda (volumetric) part on this rule (same cells).
  const VolumeQuadrature* reduced = nullptr;
  const std::vector<int>* material_of_reduced_point = nullptr;
  const Eigen::Matrix3Xd* vci_reduced = nullptr;                  // xi_I of the reduced rule (with vci)
  /// Gradient smoothing over the cells (correction `smoothed`): the faces of every cell. The cell
  /// node lists must hold the face points' neighbours and the pattern must couple every pair of them.
  const CellFaceQuadrature* smoothing = nullptr;
  /// The face points with the singular remedy (SINCHECK): they lie on the body's boundary edges too, where a
  /// small support can leave A singular (EfgAnalysis sets it).
  bool grow_at_faces = false;
  /// Distributed assembly: this call adds the cells of slab `part` of `parts` (contiguous slabs of the
  /// cells sorted along the body's longest axis); the parts of all ranks add up to the whole.
  int part = 0, parts = 1;
};

struct VolumeAssemblyReport {
  bool direct = true;  // the threads added straight into `values` (no per-thread copies)
  Index grown_face_points = 0;  // smoothing's face-point evaluations where the support grew (grow_at_faces)
};

/// Pass 2: adds the volume stiffness to values (pattern.nonzeros() entries in pattern order, for
/// example the value array of pattern.zero_matrix()) and the body force to f (3N).
VolumeAssemblyReport assemble_volume(const VolumeAssembly& input, const solve::BlockPattern& pattern, Real* values,
                     Eigen::VectorXd& f);

/// Adds per-thread copies of value ranges into `values`: copy t holds values [ranges[t].first,
/// ranges[t].second); each value's copies are summed in thread order (deterministic for a thread count).
void add_thread_copies(Real* values, const std::vector<std::vector<Real>>& copies,
                       const std::vector<std::pair<Index, Index>>& ranges);

/// Deterministic split of [0, count) into `parts` contiguous chunks: begin of chunk t.
Index chunk_begin(Index count, int parts, int t);

}  // namespace lamina::efg
