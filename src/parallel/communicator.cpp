#include "parallel/communicator.hpp"

#include <mpi.h>

#include <cstdlib>
#include <numeric>

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

MPI_Datatype index_type() { return sizeof(Index) == 8 ? MPI_INT64_T : MPI_INT32_T; }

void reduce_in_place(std::vector<Real>& values, MPI_Op op) {
  if (!values.empty())
    MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, op, MPI_COMM_WORLD);
}
}  // namespace

Environment::Environment(int& argc, char**& argv) {
  if (!launched_by_mpirun()) return;
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  mpi_started = true;
}

Environment::~Environment() {
  auto& hooks = finalize_hooks();
  for (auto it = hooks.rbegin(); it != hooks.rend(); ++it) (*it)();
  hooks.clear();
  if (!mpi_started) return;
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized) MPI_Finalize();
}

void Environment::before_finalize(std::function<void()> hook) { finalize_hooks().push_back(std::move(hook)); }

Communicator::Communicator(bool join_world) {
  if (!join_world || !mpi_started) return;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
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
  Real out = 0;
  MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  return out;
}

void Communicator::sum(std::vector<Real>& values) const {
  if (distributed()) reduce_in_place(values, MPI_SUM);
}

Real Communicator::max(Real value) const {
  if (!distributed()) return value;
  Real out = 0;
  MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return out;
}

void Communicator::max(std::vector<Real>& values) const {
  if (distributed()) reduce_in_place(values, MPI_MAX);
}

Index Communicator::sum(Index value) const {
  if (!distributed()) return value;
  Index out = 0;
  MPI_Allreduce(&value, &out, 1, index_type(), MPI_SUM, MPI_COMM_WORLD);
  return out;
}

std::vector<Real> Communicator::all_gather(const std::vector<Real>& values) const {
  if (!distributed()) return values;
  std::vector<Real> out(values.size() * static_cast<std::size_t>(size_));
  MPI_Allgather(values.data(), static_cast<int>(values.size()), MPI_DOUBLE, out.data(), static_cast<int>(values.size()),
                MPI_DOUBLE, MPI_COMM_WORLD);
  return out;
}

std::vector<int> Communicator::all_gather(int value) const {
  if (!distributed()) return {value};
  std::vector<int> out(static_cast<std::size_t>(size_));
  MPI_Allgather(&value, 1, MPI_INT, out.data(), 1, MPI_INT, MPI_COMM_WORLD);
  return out;
}

std::vector<Index> Communicator::all_gather_lists(const std::vector<Index>& values) const {
  if (!distributed()) return values;
  const std::vector<int> counts = all_gather(static_cast<int>(values.size()));
  std::vector<int> offsets(counts.size(), 0);
  std::partial_sum(counts.begin(), counts.end() - 1, offsets.begin() + 1);
  std::vector<Index> out(static_cast<std::size_t>(offsets.back() + counts.back()));
  MPI_Allgatherv(values.data(), static_cast<int>(values.size()), index_type(), out.data(), counts.data(), offsets.data(),
                 index_type(), MPI_COMM_WORLD);
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
  MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, data, counts.data(), offsets.data(), MPI_DOUBLE, MPI_COMM_WORLD);
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
  std::vector<MPI_Request> requests;
  for (int q = 0; q < size_; ++q) {
    const auto& list = receive[static_cast<std::size_t>(q)];
    if (q == rank_ || list.empty()) continue;
    auto& buffer = incoming[static_cast<std::size_t>(q)];
    buffer.resize(list.size() * static_cast<std::size_t>(per_node));
    requests.emplace_back();
    MPI_Irecv(buffer.data(), static_cast<int>(buffer.size()), MPI_DOUBLE, q, 71, MPI_COMM_WORLD, &requests.back());
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
    requests.emplace_back();
    MPI_Isend(buffer.data(), static_cast<int>(buffer.size()), MPI_DOUBLE, q, 71, MPI_COMM_WORLD, &requests.back());
  }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  for (int q = 0; q < size_; ++q) {
    const auto& list = receive[static_cast<std::size_t>(q)];
    if (q == rank_ || list.empty()) continue;
    const Real* in = incoming[static_cast<std::size_t>(q)].data();
    for (Index node : list)
      for (const auto& [data, rows] : arrays)
        for (int r = 0; r < rows; ++r) data[rows * node + r] = *in++;
  }
}

std::string Communicator::broadcast(const std::string& value) const {
  if (!distributed()) return value;
  int length = static_cast<int>(value.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string out = root() ? value : std::string(static_cast<std::size_t>(length), '\0');
  MPI_Bcast(out.data(), length, MPI_CHAR, 0, MPI_COMM_WORLD);
  return out;
}

void Communicator::barrier() const {
  if (distributed()) MPI_Barrier(MPI_COMM_WORLD);
}


}  // namespace lamina::parallel
