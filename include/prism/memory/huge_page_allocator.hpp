// An allocator for large arrays that are written before they are read: the film, and the BVH
// builder's working arrays. An array of 2 MB or more is asked for in transparent huge pages:
// an 800 x 800 film is 7.7 MB, whose 1,876 page faults in 4 kB pages cost 2.1-2.25 ms on this
// machine's kernel, against 0.35-0.45 ms in 2 MB pages (one process, first touch; where the
// kernel has no huge pages to give, madvise changes nothing). Elements are default-initialised,
// so an array its owner fills whole is not cleared first.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <new>
#include <utility>
#include <vector>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace prism {

template <class T>
struct HugePageAllocator {
    using value_type = T;
    static constexpr std::size_t huge_page = std::size_t(2) << 20;
    // Below a huge page, operator new; its aligned form where T asks for more than it gives
    // by default (the builder's 32-byte boxes of double lanes).
    static constexpr bool over_aligned = alignof(T) > __STDCPP_DEFAULT_NEW_ALIGNMENT__;

    HugePageAllocator() = default;
    template <class U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

    T* allocate(std::size_t count) {
        const std::size_t bytes = count * sizeof(T);
        if (bytes < huge_page) {
            if constexpr (over_aligned) return static_cast<T*>(::operator new(bytes, std::align_val_t(alignof(T))));
            else return static_cast<T*>(::operator new(bytes));
        }
        const std::size_t rounded = (bytes + huge_page - 1) / huge_page * huge_page;
        void* memory = std::aligned_alloc(huge_page, rounded);
        if (!memory) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
        ::madvise(memory, rounded, MADV_HUGEPAGE);  // advice only: its failure changes nothing
#endif
        return static_cast<T*>(memory);
    }
    void deallocate(T* memory, std::size_t count) noexcept {
        if (count * sizeof(T) >= huge_page) return std::free(memory);
        if constexpr (over_aligned) ::operator delete(memory, std::align_val_t(alignof(T)));
        else ::operator delete(memory);
    }
    // Default-initialisation: no value is written (glm's vectors have trivial constructors).
    template <class U>
    void construct(U* at) noexcept {
        ::new (static_cast<void*>(at)) U;
    }
    template <class U, class... Arguments>
    void construct(U* at, Arguments&&... arguments) {
        ::new (static_cast<void*>(at)) U(std::forward<Arguments>(arguments)...);
    }
    template <class U>
    bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
};

// A vector of such an array: its elements are not cleared on resize, only written by its owner.
template <class T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace prism
