// Transparent huge pages for large fresh buffers (mesh arrays, output images, container bytes): faulting
// tens or hundreds of MB in 4 KiB pages costs about as much CPU time as the arithmetic that fills them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#if __has_include(<sys/mman.h>)
#include <sys/mman.h>
#endif

namespace specbake::detail {

// Gives madvise `advice` for the whole `page`-sized pages inside [p, p + bytes) (page a power of two; the
// partial pages at either end are left alone, they may hold live data). Returns the end of the last page
// advised, or nullptr when the range holds no whole page (or the system has no madvise).
inline const void* advise_whole_pages([[maybe_unused]] const void* p, [[maybe_unused]] size_t bytes,
                                      [[maybe_unused]] uintptr_t page, [[maybe_unused]] int advice) {
#if __has_include(<sys/mman.h>)
    const uintptr_t begin = (reinterpret_cast<uintptr_t>(p) + page - 1) & ~(page - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(page - 1);
    if (end <= begin) return nullptr;
    madvise(reinterpret_cast<void*>(begin), end - begin, advice);
    return reinterpret_cast<const void*>(end);
#else
    return nullptr;
#endif
}

// Asks for transparent huge pages on the 2 MiB-aligned part of [p, p + bytes), memory not yet touched (a
// hint: nothing changes where the kernel declines). Small ranges are left alone.
inline void hint_huge_pages([[maybe_unused]] const void* p, [[maybe_unused]] size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    advise_whole_pages(p, bytes, uintptr_t(2) << 20, MADV_HUGEPAGE);
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
