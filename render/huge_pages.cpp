#include "render/huge_pages.h"

#include <sys/mman.h>

#include <cstdlib>
#include <new>

namespace cmam::render {

void* allocate_huge(std::size_t bytes) {
    constexpr std::size_t kHuge = std::size_t{2} << 20;
    if (bytes < kHuge) {
        if (void* p = std::malloc(bytes == 0 ? 1 : bytes)) return p;
        throw std::bad_alloc();
    }
    const std::size_t rounded = (bytes + kHuge - 1) / kHuge * kHuge;
    void* p = std::aligned_alloc(kHuge, rounded);
    if (!p) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    madvise(p, rounded, MADV_HUGEPAGE);  // advice only: may be ignored
#endif
    return p;
}

void free_huge(void* p) noexcept {
    std::free(p);
}

}  // namespace cmam::render
