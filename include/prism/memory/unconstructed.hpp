// Room for up to N objects that the caller constructs one by one, where an array would first
// construct (value-initialise) every element: the integrator's per-pixel and per-light records,
// most of which a given point or row never uses (eight shadow rays value-initialised per shading
// point had cost 56 instructions a point). Nothing is destroyed: for trivially destructible types.
#pragma once

#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>

namespace prism {

template <class T, std::size_t N>
    requires std::is_trivially_destructible_v<T>
union Unconstructed {
    Unconstructed() {}
    T items[N];

    // Constructs item i from `arguments` (over whatever it held) and returns it.
    template <class... Arguments>
    T& make(std::size_t i, Arguments&&... arguments) {
        return *::new (static_cast<void*>(&items[i])) T(std::forward<Arguments>(arguments)...);
    }
    // Constructs item i from what `make_value()` returns, in place (no copy of the value).
    template <class MakeValue>
    T& make_from(std::size_t i, MakeValue make_value) {
        return *::new (static_cast<void*>(&items[i])) T(make_value());
    }
    T& operator[](std::size_t i) { return items[i]; }
    const T& operator[](std::size_t i) const { return items[i]; }
    T* data() { return items; }
};

}  // namespace prism
