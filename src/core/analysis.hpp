#pragma once
// The interface every method family implements: run to completion while reporting output
// points, evaluate probes, and expose fields for VTU output.
#include <map>
#include <string>
#include <vector>

#include "core/probe.hpp"
#include "core/state_archive.hpp"
#include "core/types.hpp"

namespace lamina {

/// One named point field for output (components = 1, 3 or 6 (xx yy zz xy yz zx)).
struct PointField {
  std::string name;
  int components = 1;
  std::vector<Real> values;  // size = points * components, point-major
};

/// What a VTU file shows at one output point: points (as vertex cells, or with quad/hex cells).
struct OutputFrame {
  PointMatrix points;
  int cell_vertices = 1;                 // 1 = VTK_VERTEX per point, 4 = VTK_QUAD, 8 = VTK_HEXAHEDRON
  std::vector<Index> cell_connectivity;  // cell_vertices per cell (empty for vertex cells)
  std::vector<PointField> point_fields;
};

struct RunCounts {
  Index nodes = 0;
  Index dofs = 0;
  Index steps = 0;
};

/// Receives the analysis' output points and progress (implemented by the application).
class OutputSink {
 public:
  virtual ~OutputSink() = default;
  /// Called at each output point: the application evaluates probes and writes a VTU frame.
  virtual void output_point(Index step, Real time, Real load_factor) = 0;
  /// Progress of a long run: fraction done in [0,1] and a short status text.
  virtual void progress(Real fraction, const std::string& status) = 0;
  /// An event of the run the user should read afterwards (a solver that stopped, a fall-back taken):
  /// one line, kept in the run's log.
  virtual void notice(const std::string& /*text*/) {}
  /// Called after every step / increment (and after output_point where both fall together), when the
  /// analysis' state is complete: the application may write a checkpoint here (Analysis::save_state)
  /// or stop the run by throwing RunInterrupted.
  virtual void safe_point() {}
};

/// Thrown out of Analysis::run from a safe point when the run was asked to stop (SIGTERM / SIGINT).
struct RunInterrupted {
  int signal = 0;
};

class Analysis {
 public:
  virtual ~Analysis() = default;
  virtual std::string method() const = 0;
  /// Run to the end, calling sink.output_point at every output point (at least once, at the end).
  virtual void run(OutputSink& sink) = 0;
  /// Evaluate one probe in the current state. Throws InputError for an unsupported field/component.
  virtual Real probe(const Probe& probe) const = 0;
  /// Probes the method always reports (e.g. mls_fit's errU, errDU, errDDU).
  virtual std::map<std::string, Real> builtin_probes() const { return {}; }
  virtual OutputFrame frame() const = 0;
  /// Several ranks: whether frame() is this rank's own piece (a partitioned analysis) rather than the
  /// whole body, which every rank of a replicated analysis holds (the output splits it then).
  virtual bool frame_is_rank_piece() const { return false; }
  virtual RunCounts counts() const = 0;
  /// Named timings (seconds) of the stages, e.g. {"setup_s", ...}; summary.json lists them.
  virtual std::map<std::string, Real> timings() const { return {}; }
  /// Notes on settings that are valid but likely to mislead (e.g. a nearly incompressible material
  /// without a locking remedy), one sentence each; known after construction. The application prints
  /// them, writes them to log.txt and lists them in summary.json.
  virtual std::vector<std::string> warnings() const { return {}; }

  // Checkpoint / restart (incremental analyses). save_state is called from OutputSink::safe_point;
  // restore_state before run(), which then continues from the saved step. A restored run repeats the
  // uninterrupted one bit for bit at the same thread count.
  virtual bool can_checkpoint() const { return false; }
  /// Several ranks: called on every rank around save_state (collective), so that a partitioned analysis
  /// can hold its state whole for the checkpoint that rank 0 writes, and go back afterwards.
  virtual void before_checkpoint() {}
  virtual void after_checkpoint() {}
  virtual void save_state(StateWriter& out) const {}
  /// Throws StateError when the state does not fit this analysis.
  virtual void restore_state(const StateReader& in) {}
};

}  // namespace lamina
