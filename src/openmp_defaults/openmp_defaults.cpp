// lamina's OpenMP defaults, set before libgomp reads its environment: idle threads spin 10,000 times
// before they sleep (GOMP_SPINCOUNT), unless OMP_WAIT_POLICY or GOMP_SPINCOUNT is set.
//
// Why: libgomp's default (300,000 spins) keeps the other cores busy between the parallel regions; on a
// 2-core machine an EFG plate of 432 dofs took 36.4 ms instead of 32.5 ms on 2 threads, and the explicit
// MPM and PD loops run as fast with 10,000. libgomp reads its environment once, in its constructor, so
// this is the constructor of a small shared library that the lamina executable lists after libgomp:
// the dynamic loader runs the constructors of independent libraries in reverse order of that list
// (glibc), so this one runs after libc's (which sets the environment up) and before libgomp's. A
// .preinit_array function would be too early: libc's constructor resets the environment after it.
#include <cstdlib>

namespace {

__attribute__((constructor)) void set_openmp_spin_count() {
  if (std::getenv("OMP_WAIT_POLICY") == nullptr && std::getenv("GOMP_SPINCOUNT") == nullptr)
    setenv("GOMP_SPINCOUNT", "10000", 0);
}

}  // namespace
