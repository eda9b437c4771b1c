#include "parallel/communicator.hpp"

#include <cstdlib>
#include <numeric>

#include "core/error.hpp"
#include "core/runtime_module.hpp"
#include "parallel/mpi_module.hpp"

namespace lamina::parallel {

namespace {
bool mpi_started = false;

std::vector<std::function<void()>>& finalize_hooks() {
  static std::vector<std::function<void()>> hooks;
  return hooks;
}

bool launched_by_mpirun() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(name) != nullptr) return true;
  return false;
}

void reduce_in_place(std::vector<Real>& values, Reduction op) {
  if (!values.empty()) mpi_module().all_reduce(values.data(), static_cast<int>(values.size()), WireType::real, op);
}
}  // namespace

const MpiModule& mpi_module() {
  // Opened by the first call, once even if threads race to it (a function-local static); a failed load
  // throws and the next call tries again. Stays loaded until the process ends.
  static const MpiModule* const loaded = [] {
    std::string why;
    const MpiModule* table = open_module_table<MpiModule>(LAMINA_MPI_TRANSPORT_NAME, LAMINA_MPI_TRANSPORT_PATH,
                                                          "lamina_mpi_transport", MpiModule::abi_version, why);
    if (!table)
      throw SolverUnavailable("the MPI module " + std::string(LAMINA_MPI_TRANSPORT_NAME) + " could not be loaded: " + why);
    return table;
  }();
  return *loaded;
}

Environment::Environment(int& argc, char**& argv) {
  if (!launched_by_mpirun()) return;
  if (mpi_module().start(&argc, &argv) != 0) throw AnalysisError("MPI_Init_thread failed");
  mpi_started = true;
}

Environment::~Environment() {
  auto& hooks = finalize_hooks();
  for (auto it = hooks.rbegin(); it != hooks.rend(); ++it) (*it)();
  hooks.clear();
  if (mpi_started) mpi_module().finish();
}

void Environment::before_finalize(std::function<void()> hook) { finalize_hooks().push_back(std::move(hook)); }

Communicator::Communicator(bool join_world) {
  if (!join_world || !mpi_started) return;
  rank_ = mpi_module().rank();
  size_ = mpi_module().size();
}

const Communicator& Communicator::world() {
  static const Communicator world(true);
  return world;
}

const Communicator& Communicator::single() {
  static const Communicator alone(false);
  return alone;
}

Real Communicator::sum(Real value) const {
  if (!distributed()) return value;
  mpi_module().all_reduce(&value, 1, WireType::real, Reduction::sum);
  return value;
}

void Communicator::sum(std::vector<Real>& values) const {
  if (distributed()) reduce_in_place(values, Reduction::sum);
}

Real Communicator::max(Real value) const {
  if (!distributed()) return value;
  mpi_module().all_reduce(&value, 1, WireType::real, Reduction::max);
  return value;
}

void Communicator::max(std::vector<Real>& values) const {
  if (distributed()) reduce_in_place(values, Reduction::max);
}

Index Communicator::sum(Index value) const {
  if (!distributed()) return value;
  mpi_module().all_reduce(&value, 1, WireType::index, Reduction::sum);
  return value;
}

std::vector<Real> Communicator::all_gather(const std::vector<Real>& values) const {
  if (!distributed()) return values;
  std::vector<Real> out(values.size() * static_cast<std::size_t>(size_));
  mpi_module().all_gather(values.data(), static_cast<int>(values.size()), WireType::real, out.data());
  return out;
}

std::vector<int> Communicator::all_gather(int value) const {
  if (!distributed()) return {value};
  std::vector<int> out(static_cast<std::size_t>(size_));
  mpi_module().all_gather(&value, 1, WireType::int32, out.data());
  return out;
}

std::vector<Index> Communicator::all_gather_lists(const std::vector<Index>& values) const {
  if (!distributed()) return values;
  const std::vector<int> counts = all_gather(static_cast<int>(values.size()));
  std::vector<int> offsets(counts.size(), 0);
  std::partial_sum(counts.begin(), counts.end() - 1, offsets.begin() + 1);
  std::vector<Index> out(static_cast<std::size_t>(offsets.back() + counts.back()));
  mpi_module().all_gather_v(values.data(), static_cast<int>(values.size()), WireType::index, out.data(), counts.data(),
                            offsets.data());
  return out;
}

void Communicator::all_gather_blocks(Real* data, int rows, Index count) const {
  if (!distributed()) return;
  std::vector<Index> begins(static_cast<std::size_t>(size_) + 1);
  for (int r = 0; r <= size_; ++r) begins[static_cast<std::size_t>(r)] = block_begin(count, r);
  all_gather_blocks(data, rows, begins);
}

void Communicator::all_gather_blocks(Real* data, int rows, const std::vector<Index>& begins) const {
  if (!distributed()) return;
  std::vector<int> counts(static_cast<std::size_t>(size_)), offsets(static_cast<std::size_t>(size_));
  for (std::size_t r = 0; r < static_cast<std::size_t>(size_); ++r) {
    offsets[r] = static_cast<int>(rows * begins[r]);
    counts[r] = static_cast<int>(rows * (begins[r + 1] - begins[r]));
  }
  mpi_module().all_gather_v(nullptr, 0, WireType::real, data, counts.data(), offsets.data());
}

void Communicator::exchange_columns(std::initializer_list<std::pair<Real*, int>> arrays,
                                    const std::vector<std::vector<Index>>& send,
                                    const std::vector<std::vector<Index>>& receive) const {
  if (!distributed()) return;
  int per_node = 0;
  for (const auto& a : arrays) per_node += a.second;
  thread_local std::vector<std::vector<Real>> outgoing, incoming;
  outgoing.resize(static_cast<std::size_t>(size_));
  incoming.resize(static_cast<std::size_t>(size_));
  std::vector<Real*> receive_buffers;
  std::vector<const Real*> send_buffers;
  std::vector<int> receive_counts, receive_ranks, send_counts, send_ranks;
  for (int q = 0; q < size_; ++q) {
    const auto& list = receive[static_cast<std::size_t>(q)];
    if (q == rank_ || list.empty()) continue;
    auto& buffer = incoming[static_cast<std::size_t>(q)];
    buffer.resize(list.size() * static_cast<std::size_t>(per_node));
    receive_buffers.push_back(buffer.data());
    receive_counts.push_back(static_cast<int>(buffer.size()));
    receive_ranks.push_back(q);
  }
  for (int q = 0; q < size_; ++q) {
    const auto& list = send[static_cast<std::size_t>(q)];
    if (q == rank_ || list.empty()) continue;
    auto& buffer = outgoing[static_cast<std::size_t>(q)];
    buffer.resize(list.size() * static_cast<std::size_t>(per_node));
    Real* out = buffer.data();
    for (Index node : list)
      for (const auto& [data, rows] : arrays)
        for (int r = 0; r < rows; ++r) *out++ = data[rows * node + r];
    send_buffers.push_back(buffer.data());
    send_counts.push_back(static_cast<int>(buffer.size()));
    send_ranks.push_back(q);
  }
  mpi_module().exchange(static_cast<int>(receive_buffers.size()), receive_buffers.data(), receive_counts.data(),
                        receive_ranks.data(), static_cast<int>(send_buffers.size()), send_buffers.data(), send_counts.data(),
                        send_ranks.data(), 71);
  for (int q = 0; q < size_; ++q) {
    const auto& list = receive[static_cast<std::size_t>(q)];
    if (q == rank_ || list.empty()) continue;
    const Real* in = incoming[static_cast<std::size_t>(q)].data();
    for (Index node : list)
      for (const auto& [data, rows] : arrays)
        for (int r = 0; r < rows; ++r) data[rows * node + r] = *in++;
  }
}

std::vector<int> Communicator::all_to_all(const std::vector<int>& values) const {
  if (!distributed()) return values;
  std::vector<int> out(static_cast<std::size_t>(size_));
  const std::vector<int> ones(static_cast<std::size_t>(size_), 1);
  std::vector<int> offsets(static_cast<std::size_t>(size_));
  std::iota(offsets.begin(), offsets.end(), 0);
  mpi_module().all_to_all_v(values.data(), ones.data(), offsets.data(), out.data(), ones.data(), offsets.data(), WireType::int32);
  return out;
}

std::vector<Index> Communicator::all_to_all_lists(const std::vector<Index>& values, const std::vector<int>& send_counts,
                                                  const std::vector<int>& receive_counts) const {
  if (!distributed()) return values;
  std::vector<int> send_offsets(send_counts.size(), 0), receive_offsets(receive_counts.size(), 0);
  std::partial_sum(send_counts.begin(), send_counts.end() - 1, send_offsets.begin() + 1);
  std::partial_sum(receive_counts.begin(), receive_counts.end() - 1, receive_offsets.begin() + 1);
  std::vector<Index> out(static_cast<std::size_t>(receive_offsets.back() + receive_counts.back()));
  mpi_module().all_to_all_v(values.data(), send_counts.data(), send_offsets.data(), out.data(), receive_counts.data(),
                            receive_offsets.data(), WireType::index);
  return out;
}

std::string Communicator::broadcast(const std::string& value) const {
  if (!distributed()) return value;
  int length = static_cast<int>(value.size());
  mpi_module().broadcast(&length, 1, WireType::int32, 0);
  std::string out = root() ? value : std::string(static_cast<std::size_t>(length), '\0');
  mpi_module().broadcast(out.data(), length, WireType::character, 0);
  return out;
}

void Communicator::barrier() const {
  if (distributed()) mpi_module().barrier();
}


}  // namespace lamina::parallel
