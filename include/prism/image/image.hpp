// The HDR film: linear radiance in single-precision floating point, row-major from the top-left
// pixel. Whatever precision the renderer traced in, images are kept in float to the end.
#pragma once

#include <glm/glm.hpp>

#include <cassert>
#include <cstddef>
#include <cstdlib>
#include <new>
#include <utility>
#include <vector>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace prism {

// The film's storage. A film of 2 MB or more is asked for in transparent huge pages: an
// 800 x 800 film is 7.7 MB, whose 1,876 page faults in 4 kB pages cost 2.1-2.25 ms on this
// machine's kernel before the render could start, against 0.35-0.45 ms in 2 MB pages (one
// process, first touch; where the kernel has no huge pages to give, madvise changes nothing).
// Elements are default-initialised, so a film whose every pixel the renderer writes is not
// cleared first (Image::Unfilled).
template <class T>
struct FilmAllocator {
    using value_type = T;
    static constexpr std::size_t huge_page = std::size_t(2) << 20;

    FilmAllocator() = default;
    template <class U>
    FilmAllocator(const FilmAllocator<U>&) noexcept {}

    T* allocate(std::size_t count) {
        const std::size_t bytes = count * sizeof(T);
        if (bytes < huge_page) return static_cast<T*>(::operator new(bytes));
        const std::size_t rounded = (bytes + huge_page - 1) / huge_page * huge_page;
        void* memory = std::aligned_alloc(huge_page, rounded);
        if (!memory) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
        ::madvise(memory, rounded, MADV_HUGEPAGE);  // advice only: its failure changes nothing
#endif
        return static_cast<T*>(memory);
    }
    void deallocate(T* memory, std::size_t count) noexcept {
        if (count * sizeof(T) < huge_page) ::operator delete(memory);
        else std::free(memory);
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
    bool operator==(const FilmAllocator<U>&) const noexcept { return true; }
};

struct Image {
    int width = 0;
    int height = 0;
    std::vector<glm::vec3, FilmAllocator<glm::vec3>> pixels;

    // A film whose pixels the caller writes, every one, before reading any (the renderer's).
    struct Unfilled {};

    Image() = default;
    Image(int width_, int height_)
        : width(width_), height(height_),
          pixels(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), glm::vec3(0.0f)) {}
    Image(int width_, int height_, Unfilled)
        : width(width_), height(height_), pixels(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_)) {}

    glm::vec3& operator()(int x, int y) {
        assert(x >= 0 && x < width && y >= 0 && y < height);
        return pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
    }
    const glm::vec3& operator()(int x, int y) const {
        assert(x >= 0 && x < width && y >= 0 && y < height);
        return pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
    }
};

}  // namespace prism
