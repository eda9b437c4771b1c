#include "parallel/halo_exchange.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace lamina::parallel {

HaloExchange::HaloExchange(const std::vector<Index>& global, const std::vector<int>& owner, const Communicator& comm) {
  if (!comm.distributed()) return;
  comm_ = &comm;
  const int ranks = comm.size();
  send_.assign(static_cast<std::size_t>(ranks), {});
  receive_.assign(static_cast<std::size_t>(ranks), {});
  // the halo nodes of each owner (global indices, ascending as `global` is)
  std::vector<std::vector<Index>> wanted(static_cast<std::size_t>(ranks));
  std::vector<std::vector<Index>> wanted_local(static_cast<std::size_t>(ranks));
  for (std::size_t k = 0; k < global.size(); ++k)
    if (owner[k] != comm.rank()) {
      wanted[static_cast<std::size_t>(owner[k])].push_back(global[k]);
      wanted_local[static_cast<std::size_t>(owner[k])].push_back(static_cast<Index>(k));
    }
  std::vector<int> send_counts(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r) send_counts[static_cast<std::size_t>(r)] = static_cast<int>(wanted[static_cast<std::size_t>(r)].size());
  const std::vector<int> receive_counts = comm.all_to_all(send_counts);
  std::vector<Index> requests;
  for (const auto& list : wanted) requests.insert(requests.end(), list.begin(), list.end());
  const std::vector<Index> asked = comm.all_to_all_lists(requests, send_counts, receive_counts);
  std::vector<int> receive_offsets(static_cast<std::size_t>(ranks), 0);
  std::partial_sum(receive_counts.begin(), receive_counts.end() - 1, receive_offsets.begin() + 1);
  for (int r = 0; r < ranks; ++r) {
    const auto ru = static_cast<std::size_t>(r);
    receive_[ru] = wanted_local[ru];
    for (int k = 0; k < receive_counts[ru]; ++k) {
      const Index g = asked[static_cast<std::size_t>(receive_offsets[ru] + k)];
      const auto it = std::lower_bound(global.begin(), global.end(), g);
      if (it == global.end() || *it != g || owner[static_cast<std::size_t>(it - global.begin())] != comm.rank())
        throw std::logic_error("halo exchange: a rank asked for a node this rank does not own");
      send_[ru].push_back(static_cast<Index>(it - global.begin()));
    }
  }
}

void HaloExchange::exchange(Real* data, int rows) const {
  if (comm_) comm_->exchange_columns({{data, rows}}, send_, receive_);
}

Index HaloExchange::halo_nodes() const {
  Index n = 0;
  for (const auto& list : receive_) n += static_cast<Index>(list.size());
  return n;
}

Index HaloExchange::sent_nodes() const {
  Index n = 0;
  for (const auto& list : send_) n += static_cast<Index>(list.size());
  return n;
}

}  // namespace lamina::parallel
