// A ray handed to the integrator's recursion in one store. `trace` takes its Ray by value, so
// every call copies the ray into the call's argument with one 32-byte load (GCC, x86-64). A ray
// just written field by field (the camera's origin, then its direction behind a square root and
// a division; leaving_ray's answer, stored through the return slot) cannot be forwarded to that
// load from the narrower stores: the load waits for them to reach the cache. Gathered into one
// vector first, the ray's first 32 bytes are one store the load reads at once. Measured: the
// load after the camera's field stores was a quarter of the per-pixel samples of hw1 simple.json
// and simple_shading; after leaving_ray's, 29% of trace's samples in hw2 mirror_room.
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/geometry/ray.hpp>

#include <cstring>
#include <type_traits>

namespace prism {

// The same ray, bit for bit. Float rays (36 bytes) only; double ones are returned as they are.
template <Scalar Real>
PRISM_FORCE_INLINE inline Ray<Real> stored_whole(const Ray<Real>& ray) {
#if defined(__GNUC__) || defined(__clang__)  // vector extensions; elsewhere the ray as it is
    if constexpr (std::is_same_v<Real, float> && sizeof(Ray<float>) == 9 * sizeof(float)) {
        typedef float Lanes __attribute__((vector_size(32)));
        const Lanes lanes = {ray.origin.x,    ray.origin.y,    ray.origin.z, ray.direction.x,
                             ray.direction.y, ray.direction.z, ray.t_min,    ray.t_max};
        Ray<Real> whole;
        std::memcpy(static_cast<void*>(&whole), &lanes, sizeof(lanes));
        whole.time = ray.time;
        return whole;
    } else {
        return ray;
    }
#else
    return ray;
#endif
}

}  // namespace prism
