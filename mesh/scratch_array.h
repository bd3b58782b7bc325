// ScratchArray: the large temporary arrays of the mesh algorithms (corner records, pairings; tens of MB for
// a million triangles). Left uninitialised and marked for transparent huge pages before first touch:
// faulting them in 4 KiB pages costs about as much CPU time as the curvature arithmetic itself.
// hint_huge_pages / reserve_huge_pages give the same hint to memory that must live in a std::vector.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
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

template <class T>
class ScratchArray {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

public:
    explicit ScratchArray(size_t n) : size_(n) {
        constexpr size_t kHuge = size_t(2) << 20;
        const size_t bytes = std::max<size_t>(n * sizeof(T), 1);
        const size_t align = bytes >= kHuge ? kHuge : alignof(std::max_align_t);
        const size_t rounded = (bytes + align - 1) / align * align;
        data_.reset(static_cast<T*>(std::aligned_alloc(align, rounded)));
        if (!data_) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
        if (align == kHuge) madvise(data_.get(), rounded, MADV_HUGEPAGE);  // a hint; failure is harmless
#endif
    }
    T& operator[](size_t i) { return data_[i]; }
    const T& operator[](size_t i) const { return data_[i]; }
    T* data() { return data_.get(); }
    const T* data() const { return data_.get(); }
    size_t size() const { return size_; }

private:
    struct Free {
        void operator()(T* p) const { std::free(p); }
    };
    std::unique_ptr<T[], Free> data_;
    size_t size_;
};

}  // namespace specbake::detail
