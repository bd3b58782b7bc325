// The global operator new and delete of the mesh fuzz target (linked into fuzz_mesh only): every form goes
// to malloc / free (the sanitizer's), and a freed block of 1 MiB or more is kept, poisoned, for the next
// request of its size.
// Why: Assimp's OBJ and PLY readers construct an IOStreamBuffer<char> for every file, whose cache is a
// std::vector<char> of 4096 * 4096 bytes, zero-filled and then filled with '\n' (assimp/IOStreamBuffer.h),
// however small the file. Under AddressSanitizer a block that large is a fresh mmap each time (its
// LargeMmapAllocator keeps none), so each execution faulted in 4096 new pages and poisoned 2 MiB of shadow
// twice: about 80 % of an execution's time, against under 1 % for the Importer's construction and the
// scratch file. Handing the same block back keeps its pages. Detection is kept: a cached block is
// poisoned while it waits (a read after delete is reported, as use-after-poison), the sanitizer's redzone
// after it stays, and every other block is an ordinary sanitizer allocation. What is given up is the
// new/delete versus malloc/free mismatch report (alloc_dealloc_mismatch), which needs the sanitizer's own
// operator new; the test suite under the sanitizers still has it.
#include <sanitizer/allocator_interface.h>
#include <sanitizer/asan_interface.h>

#include <array>
#include <cstddef>
#include <cstdlib>
#include <mutex>
#include <new>

namespace specbake::fuzz {
namespace {

class LargeBlockReuse {
public:
    static constexpr size_t kFrom = size_t(1) << 20;

    static void* allocate(size_t n) {
        if (n >= kFrom) {
            std::lock_guard lock(mutex());
            for (Slot& s : slots())
                if (s.block && s.size == n) {
                    void* p = s.block;
                    s.block = nullptr;
                    ASAN_UNPOISON_MEMORY_REGION(p, n);
                    return p;
                }
        }
        void* p = std::malloc(n ? n : 1);
        if (!p) throw std::bad_alloc();
        return p;
    }

    static void release(void* p) {
        if (!p) return;
        const size_t n = __sanitizer_get_allocated_size(p);
        if (n >= kFrom) {
            std::lock_guard lock(mutex());
            for (Slot& s : slots())
                if (!s.block) {
                    ASAN_POISON_MEMORY_REGION(p, n);
                    s.block = p;
                    s.size = n;
                    return;
                }
        }
        std::free(p);
    }

private:
    struct Slot {
        void* block = nullptr;
        size_t size = 0;
    };
    static std::array<Slot, 4>& slots() {
        static std::array<Slot, 4> s;
        return s;
    }
    static std::mutex& mutex() {
        static std::mutex m;
        return m;
    }
};

inline void* aligned_block(size_t n, std::align_val_t a) {
    const size_t align = static_cast<size_t>(a);
    void* p = std::aligned_alloc(align, (n + align - 1) / align * align);
    if (!p) throw std::bad_alloc();
    return p;
}

}  // namespace
}  // namespace specbake::fuzz

// At most four blocks wait at a time; aligned forms are never kept.
void* operator new(size_t n) { return specbake::fuzz::LargeBlockReuse::allocate(n); }
void* operator new[](size_t n) { return specbake::fuzz::LargeBlockReuse::allocate(n); }
void* operator new(size_t n, const std::nothrow_t&) noexcept {
    try {
        return specbake::fuzz::LargeBlockReuse::allocate(n);
    } catch (...) {
        return nullptr;
    }
}
void* operator new[](size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void* operator new(size_t n, std::align_val_t a) { return specbake::fuzz::aligned_block(n, a); }
void* operator new[](size_t n, std::align_val_t a) { return specbake::fuzz::aligned_block(n, a); }
void* operator new(size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
    try {
        return specbake::fuzz::aligned_block(n, a);
    } catch (...) {
        return nullptr;
    }
}
void* operator new[](size_t n, std::align_val_t a, const std::nothrow_t& t) noexcept { return operator new(n, a, t); }
void operator delete(void* p) noexcept { specbake::fuzz::LargeBlockReuse::release(p); }
void operator delete[](void* p) noexcept { specbake::fuzz::LargeBlockReuse::release(p); }
void operator delete(void* p, size_t) noexcept { specbake::fuzz::LargeBlockReuse::release(p); }
void operator delete[](void* p, size_t) noexcept { specbake::fuzz::LargeBlockReuse::release(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { specbake::fuzz::LargeBlockReuse::release(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { specbake::fuzz::LargeBlockReuse::release(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
