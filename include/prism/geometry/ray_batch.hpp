// The one query seam between the integrators and a scene's index (SceneGeometry, or Embree's):
// a batch of one to max_rays rays, of which those in the active mask are traced, with the
// culling rule of their kind. An index answers two questions of a batch, each with one entry:
// - intersect(batch, hits): the closest hits. Each active ray's t_max is lowered to its hit and
//   hits[i] filled; bit i of the answer is set where rays[i] hits.
// - occluded(batch): whether anything lies in (t_min, t_max) of each active ray; bit i of the
//   answer is set where rays[i] is blocked.
// One ray is a batch of one (closest_hit, blocked). How a batch is traversed (SIMD lanes, or
// ray by ray) is the index's decision, taken in one place; whatever it decides, every ray's
// answer is the one it gets alone, to the bit (the tie rule: geometry/scene_index_lanes.hpp).
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/geometry/backface_culling.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/ray.hpp>

#include <bit>
#include <cstdint>

namespace prism {

template <Scalar Real>
struct RayBatch {
    static constexpr int max_rays = 32;

    Ray<Real>* rays;  // rays[0, count); an any-hit query never writes them
    int count = 1;
    std::uint32_t active = 1;  // bit i: rays[i] is traced; rays outside it need not be made
    BackfaceCulling culling = BackfaceCulling::none;

    // rays[0, count), all active.
    static RayBatch all(Ray<Real>* rays, int count, BackfaceCulling culling = BackfaceCulling::none) {
        return {rays, count, count >= 32 ? ~std::uint32_t(0) : (std::uint32_t(1) << count) - 1, culling};
    }
    // Whether the active rays are rays[0, count) without a gap.
    bool dense() const { return active == (count >= 32 ? ~std::uint32_t(0) : (std::uint32_t(1) << count) - 1); }
};

// How an index traverses a batch of several rays: ray by ray, with a ray in each SIMD lane at
// leaves tested directly, or several rays through the index together. Only the index chooses
// (SceneIndex::route); tests read its choice to know which traversal they check.
enum class BatchRoute { ray_by_ray, leaf_lanes, index_lanes };

// The culling rule of an integrator's rays: camera rays (depth 0) skip back faces as `culling`
// says; every other ray sees both sides, so the two integrators see the same first surfaces.
inline BackfaceCulling culling_at_depth(BackfaceCulling culling, int depth) {
    return depth == 0 ? culling : BackfaceCulling::none;
}

// One ray's closest hit: a batch of one. Inlined, so that the batch's count and mask are known
// to the index's entry, which then reduces to its one-ray traversal.
template <class Index, Scalar Real>
PRISM_FORCE_INLINE inline bool closest_hit(const Index& index, Ray<Real>& ray, Hit<Real>& hit,
                                               BackfaceCulling culling = BackfaceCulling::none) {
    return index.intersect(RayBatch<Real>{&ray, 1, 1, culling}, &hit) != 0;
}

// Whether one ray is blocked: a batch of one.
template <class Index, Scalar Real>
PRISM_FORCE_INLINE inline bool blocked(const Index& index, const Ray<Real>& ray) {
    return index.occluded(RayBatch<Real>{const_cast<Ray<Real>*>(&ray), 1, 1, BackfaceCulling::none}) != 0;
}

}  // namespace prism
