// ScratchArray: the large temporary arrays of the mesh algorithms (corner records, pairings; tens of MB for
// a million triangles). Left uninitialised and marked for transparent huge pages before first touch:
// faulting them in 4 KiB pages costs about as much CPU time as the curvature arithmetic itself.
#pragma once

#include "core/huge_pages.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>

namespace specbake::detail {

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
        if (align == kHuge) hint_huge_pages(data_.get(), rounded);
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
