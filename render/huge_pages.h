// render — memory for large arrays read at random (decoded images, environment maps'
// distributions, meshes): from 2 MiB on, aligned to and advised to use 2 MiB pages, so that
// reading them takes few page-table walks and filling them few page faults.
#pragma once

#include <cstddef>
#include <vector>

namespace cmam::render {

/// `bytes` of memory (on 2 MiB pages from 2 MiB on), freed by free_huge; throws std::bad_alloc.
void* allocate_huge(std::size_t bytes);
void free_huge(void* p) noexcept;

template <class T>
struct HugePageAllocator {
    using value_type = T;
    HugePageAllocator() = default;
    template <class U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept {}
    T* allocate(std::size_t n) { return static_cast<T*>(allocate_huge(n * sizeof(T))); }
    void deallocate(T* p, std::size_t) noexcept { free_huge(p); }
    template <class U>
    bool operator==(const HugePageAllocator<U>&) const noexcept {
        return true;
    }
};

/// A vector whose storage is allocate_huge's.
template <class T>
using HugeVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace cmam::render
