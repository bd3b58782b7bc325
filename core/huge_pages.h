// Transparent huge pages for large fresh buffers (mesh arrays, output images, container bytes): faulting
// tens or hundreds of MB in 4 KiB pages costs about as much CPU time as the arithmetic that fills them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace specbake::detail {

// Asks for transparent huge pages on the 2 MiB-aligned part of [p, p + bytes), memory not yet touched (a
// hint: nothing changes where the kernel declines). Small ranges are left alone.
inline void hint_huge_pages([[maybe_unused]] const void* p, [[maybe_unused]] size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    constexpr uintptr_t kHuge = uintptr_t(2) << 20;
    const uintptr_t begin = (reinterpret_cast<uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(kHuge - 1);
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#endif
}

// Reserves room for n elements in an empty vector and hints huge pages on it, so the elements written next
// (resize, insert) fault in 2 MiB at a time.
template <class T>
void reserve_huge_pages(std::vector<T>& v, size_t n) {
    v.reserve(n);
    hint_huge_pages(v.data(), v.capacity() * sizeof(T));
}

}  // namespace specbake::detail
