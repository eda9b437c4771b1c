#include "core/memory.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace lamina {

void advise_huge_pages(void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t huge_page = std::uintptr_t{1} << 21;
  if (data == nullptr || bytes < 2 * huge_page) return;
  const auto begin = reinterpret_cast<std::uintptr_t>(data);
  const std::uintptr_t first = (begin + huge_page - 1) & ~(huge_page - 1);
  const std::uintptr_t last = (begin + bytes) & ~(huge_page - 1);
  if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);  // a hint: errors ignored
#else
  (void)data;
  (void)bytes;
#endif
}

void use_huge_page_heap(std::size_t reserve) {
#if defined(__GLIBC__) && defined(__linux__) && defined(MADV_HUGEPAGE)
  const char* setting = std::getenv("LAMINA_HUGE_PAGE_HEAP");
  if (setting != nullptr && std::strcmp(setting, "0") == 0) return;
  constexpr int mmap_threshold = 64 << 20;
  mallopt(M_MMAP_THRESHOLD, mmap_threshold);  // fixed: no longer adapted to the freed sizes
  mallopt(M_TRIM_THRESHOLD, static_cast<int>(std::min<std::size_t>(2 * reserve, std::size_t{1} << 30)));
  mallopt(M_TOP_PAD, static_cast<int>(std::min<std::size_t>(reserve, std::size_t{1} << 30)));
  // One allocation that the heap cannot hold grows it by the reserve; the new part is not yet touched,
  // except where malloc wrote the headers of the probe and of the top chunk behind it.
  constexpr std::size_t probe_bytes = std::size_t{2} << 20;
  void* probe = std::malloc(probe_bytes);
  if (probe == nullptr) return;
  const auto first = reinterpret_cast<std::uintptr_t>(probe);
  const auto top = reinterpret_cast<std::uintptr_t>(sbrk(0));
  std::free(probe);
  if (top <= first) return;
  advise_huge_pages(reinterpret_cast<void*>(first), top - first);
  // A 2 MiB page that was touched before the advice stays in small pages. A block that is never freed
  // covers those (it reaches past the top chunk's old header), so that the allocations that follow start
  // on the next 2 MiB boundary; only its own header is ever touched.
  constexpr std::uintptr_t huge_page = std::uintptr_t{1} << 21;
  const std::uintptr_t boundary = (first + probe_bytes + 64 + huge_page - 1) & ~(huge_page - 1);
  if (boundary < top) {
    [[maybe_unused]] static void* volatile filler = nullptr;  // volatile: an unused allocation would be optimised away
    filler = std::malloc(boundary - first - 32);
  }
#else
  (void)reserve;
#endif
}

std::size_t physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  return pages > 0 && page > 0 ? static_cast<std::size_t>(pages) * static_cast<std::size_t>(page) : 0;
}

}  // namespace lamina

namespace lamina {

std::size_t peak_resident_bytes() {
  struct rusage usage {};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return static_cast<std::size_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

}  // namespace lamina
