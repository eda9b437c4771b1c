// The module lamina_cholmod_factor: CHOLMOD's supernodal Cholesky behind solve::SparseCholesky
// (solve/sparse_cholesky.hpp), loaded with dlopen at the first sparse factorisation.
#include <Eigen/CholmodSupport>

#include <cstdlib>
#include <cstring>

#include "core/memory.hpp"
#include "solve/sparse_cholesky.hpp"

namespace lamina::solve {

namespace {

// CHOLMOD allocates its factor and workspace through SuiteSparse_config. Large blocks are advised for
// huge pages before their first touch (see core/memory.hpp): on this kind of machine 4 KiB page
// faults were a large part of the factorisation time.
constexpr std::size_t huge_allocation = std::size_t{4} << 20;
void* malloc_advised(std::size_t bytes) {
  void* p = std::malloc(bytes);
  if (bytes >= huge_allocation) advise_huge_pages(p, bytes);
  return p;
}
void* calloc_advised(std::size_t count, std::size_t size) {
  const std::size_t bytes = count * size;
  if (size != 0 && bytes / size != count) return nullptr;
  if (bytes < huge_allocation) return std::calloc(count, size);
  void* p = std::malloc(bytes);
  if (!p) return nullptr;
  advise_huge_pages(p, bytes);
  std::memset(p, 0, bytes);
  return p;
}
void* realloc_advised(void* old, std::size_t bytes) {
  void* p = std::realloc(old, bytes);
  if (bytes >= huge_allocation) advise_huge_pages(p, bytes);
  return p;
}
/// Installs the allocators above once, before the first factorisation (single-threaded caller).
void install_cholmod_allocators() {
  static const bool installed = [] {
    SuiteSparse_config.malloc_func = malloc_advised;
    SuiteSparse_config.calloc_func = calloc_advised;
    SuiteSparse_config.realloc_func = realloc_advised;
    SuiteSparse_config.free_func = std::free;
    return true;
  }();
  (void)installed;
}

/// Eigen's wrapper, with CHOLMOD's condition estimate of the factor (a protected member there).
class SupernodalLlt : public Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Upper> {
 public:
  Real rcond() { return m_cholmodFactor ? cholmod_rcond(m_cholmodFactor, &cholmod()) : 0.0; }
};

class CholmodSupernodal final : public SparseCholesky {
 public:
  CholmodSupernodal() {
    install_cholmod_allocators();
    llt_.cholmod().print = 0;
    // Both orderings, the one with the sparser factor kept. CHOLMOD's own default tries METIS only when
    // AMD's fill is large and kept AMD on the EFG systems (hundreds of neighbours per node), where METIS
    // factors 3.5 x faster (R1a 21 x 21 x 5: 2.4 s -> 0.69 s).
    llt_.cholmod().nmethods = 2;
    llt_.cholmod().method[0].ordering = CHOLMOD_AMD;
    llt_.cholmod().method[1].ordering = CHOLMOD_METIS;
  }
  bool compute(const SparseMatrix& upper) override {
    llt_.compute(upper);
    factored_ = llt_.info() == Eigen::Success;
    return factored_;
  }
  Real rcond() const override { return factored_ ? llt_.rcond() : 0.0; }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const override { return llt_.solve(b); }

 private:
  // mutable: CHOLMOD's common block records statistics in calls that do not change the factor
  mutable SupernodalLlt llt_;
  bool factored_ = false;
};

std::unique_ptr<SparseCholesky> create() { return std::make_unique<CholmodSupernodal>(); }

}  // namespace

}  // namespace lamina::solve

extern "C" __attribute__((visibility("default"))) const lamina::solve::CholmodFactorModule* lamina_cholmod_factor() {
  static const lamina::solve::CholmodFactorModule table{lamina::solve::cholmod_factor_abi, &lamina::solve::create};
  return &table;
}
