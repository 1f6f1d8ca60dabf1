// The course's <LightMesh>: a triangle mesh whose surface emits a constant Radiance from both
// faces. Direct lighting takes one sample of it in two steps:
// - a triangle, chosen in proportion to how large it looks from the shading point (A |cos| / d^3
//   at its centroid, the solid angle of a small triangle), none wholly below the point's horizon;
//   a mesh of more than `weighed_by_view` triangles chooses by area instead, which costs nothing
//   a sample. Chosen by area, a ceiling beside a hanging light box drew the one side face it sees
//   once in 12 samples;
// - a direction towards it, uniform in the solid angle it subtends (sampling/spherical_triangle.hpp),
//   so the estimate stays bounded beside the light, where sampling a point by area divides by its
//   squared distance. A triangle too small or too flat for that is sampled by area, a uniform
//   point of it (Pharr, Jakob and Humphreys, "Physically Based Rendering", 4th ed., sec. 6.5.4),
//   with the solid-angle density |x - q|^2 / (A_t |cos theta_q|) (sec. 4.2.3's change of measure).
// On glossy_area_small the two together leave 0.29 of area sampling's squared error at 64 samples
// a pixel, for 1.16 times its render time (bench/RESULTS.md, "Object lights"). pdf() applies the
// same rules, for multiple importance sampling.
// Instances of a LightMesh emit too; each mesh and instance is one light, in world space.
#pragma once

#include <prism/light/light_sample.hpp>
#include <prism/sampling/piecewise_constant.hpp>
#include <prism/sampling/spherical_triangle.hpp>
#include <prism/scene/scene.hpp>
#include <prism/simd/pack.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace prism {

// The number each object has (Hit::object): the meshes in order, then the mesh instances,
// then the spheres (place_objects, geometry/placement.hpp, numbers them in this order).
inline std::uint32_t scene_object_of_mesh(const scene::Scene&, std::size_t mesh) { return std::uint32_t(mesh); }
inline std::uint32_t scene_object_of_instance(const scene::Scene& scene, std::size_t instance) {
    return std::uint32_t(scene.meshes.size() + instance);
}
inline std::uint32_t scene_object_of_sphere(const scene::Scene& scene, std::size_t sphere) {
    return std::uint32_t(scene.meshes.size() + scene.mesh_instances.size() + sphere);
}

template <Scalar Real>
struct LightMesh {
    struct Triangle {
        Vec3<Real> a{0}, edge1{0}, edge2{0};
        Vec3<Real> normal{0, 0, 1};  // unit
        Real area = 0;
        // Beyond this squared distance from the centroid the triangle looks too small to sample
        // by solid angle (SphericalTriangle::unsamplable_beyond): most shading points of the
        // hw7 Cornell boxes see their light box so, and need no spherical triangle in double.
        Vec3<Real> centroid{0};
        Real unsamplable_beyond = 0;

        // Whether SphericalTriangle(viewpoint, a, edge1, edge2).samplable() may be true.
        bool may_be_samplable(const Vec3<Real>& viewpoint) const {
            const Vec3<Real> to_centroid = centroid - viewpoint;
            return !(glm::dot(to_centroid, to_centroid) > unsamplable_beyond);
        }
    };
    std::vector<Triangle> triangles;  // world space
    PiecewiseConstant1D<Real> by_area;
    Real area = 0;
    Vec3<Real> radiance{0};
    std::uint32_t object = 0;  // SceneGeometry's index of the mesh or instance

    static constexpr scene::LightKind kind = scene::LightKind::object;

    // World-space triangles are computed in double from the file's values and rounded once.
    static LightMesh make(const scene::Mesh& mesh, const glm::dmat4& transform, std::uint32_t object) {
        LightMesh light;
        light.radiance = Vec3<Real>(mesh.radiance);
        light.object = object;
        std::vector<Real> areas;
        double total = 0;
        for (const auto& triangle : mesh.triangles) {
            const auto world = [&](std::uint32_t v) { return glm::dvec3(transform * glm::dvec4(mesh.positions[v], 1.0)); };
            const glm::dvec3 a = world(triangle[0]), b = world(triangle[1]), c = world(triangle[2]);
            const glm::dvec3 cross = glm::cross(b - a, c - a);
            const double length = glm::length(cross);
            Triangle made{Vec3<Real>(a), Vec3<Real>(b - a), Vec3<Real>(c - a),
                          Vec3<Real>(length > 0 ? cross / length : glm::dvec3(0, 0, 1)), Real(length / 2)};
            made.centroid = Vec3<Real>((a + b + c) / 3.0);
            made.unsamplable_beyond = SphericalTriangle::unsamplable_beyond(made.a, made.edge1, made.edge2, made.centroid);
            light.triangles.push_back(made);
            if (light.triangles.size() <= weighed_by_view) light.view.add(light.triangles.size() - 1, a, b, c, cross / 2.0);
            areas.push_back(Real(length / 2));
            total += length / 2;
        }
        light.by_area = PiecewiseConstant1D<Real>(std::move(areas));
        light.area = Real(total);
        return light;
    }

    static std::vector<LightMesh> from_scene(const scene::Scene& scene) {
        std::vector<LightMesh> lights;
        for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
            const scene::Mesh& mesh = scene.meshes[m];
            if (mesh.radiance != glm::dvec3(0.0)) lights.push_back(make(mesh, mesh.transform, scene_object_of_mesh(scene, m)));
        }
        for (std::size_t i = 0; i < scene.mesh_instances.size(); ++i) {
            const scene::MeshInstance& instance = scene.mesh_instances[i];
            const scene::Mesh& mesh = scene.meshes[instance.base_mesh];
            if (mesh.radiance != glm::dvec3(0.0))
                lights.push_back(make(mesh, instance.transform, scene_object_of_instance(scene, i)));
        }
        std::erase_if(lights, [](const LightMesh& light) { return !(light.area > 0); });
        return lights;
    }

    // Up to this many triangles, a shading point weighs each by how large it looks (a pass over
    // them a sample, in sample() and pdf() alike); a larger mesh chooses by area.
    static constexpr std::size_t weighed_by_view = 16;

    // The solid-angle density with which sample() from `from` reaches `point` on triangle
    // `triangle` (the file's number), whose unit normal is `normal`.
    Real pdf(const ShadingFrame<Real>& from, const Vec3<Real>& point, const Vec3<Real>& normal,
             std::uint32_t triangle) const {
        if (triangle >= triangles.size()) return 0;
        const Real chance = chance_of(from, triangle);
        if (!(chance > 0)) return 0;
        const Triangle& t = triangles[triangle];
        if (t.may_be_samplable(from.position)) {
            const SphericalTriangle view(from.position, t.a, t.edge1, t.edge2);
            if (view.samplable()) return Real(double(chance) / view.solid_angle());
        }
        const Vec3<Real> to_light = point - from.position;
        const Real distance_squared = glm::dot(to_light, to_light);
        const Real cos_light = std::abs(glm::dot(normal, to_light)) / std::sqrt(distance_squared);
        if (!(cos_light > 0)) return 0;
        return chance * distance_squared / (t.area * cos_light);
    }

    LightSample<Real> sample(const ShadingFrame<Real>& at, const Vec2<Real>& u) const {
        const Choice choice = choose(at, u.x);
        if (!(choice.chance > 0)) return {at.normal, Real(0), Vec3<Real>(0), Real(0)};
        const Triangle& triangle = triangles[choice.triangle];
        if (triangle.may_be_samplable(at.position)) {
            const SphericalTriangle view(at.position, triangle.a, triangle.edge1, triangle.edge2);
            if (view.samplable()) {
                const Vec3<Real> direction = view.sample(Vec2<Real>(choice.reused, u.y));
                // Where the direction meets the triangle's plane.
                const Real distance =
                    glm::dot(triangle.normal, triangle.a - at.position) / glm::dot(triangle.normal, direction);
                if (!(distance > 0) || !std::isfinite(distance)) return {direction, Real(0), Vec3<Real>(0), Real(0)};
                const Real density = Real(double(choice.chance) / view.solid_angle());
                return {direction, distance, radiance / density, density};
            }
        }
        const Real root = std::sqrt(choice.reused);
        const Vec3<Real> point = triangle.a + root * (1 - u.y) * triangle.edge1 + root * u.y * triangle.edge2;
        const Vec3<Real> to_light = point - at.position;
        const Real distance_squared = glm::dot(to_light, to_light);
        const Real distance = std::sqrt(distance_squared);
        if (!(distance > 0)) return {Vec3<Real>(0, 0, 1), Real(0), Vec3<Real>(0), Real(0)};
        const Vec3<Real> direction = to_light / distance;
        const Real cos_light = std::abs(glm::dot(triangle.normal, direction));
        if (!(cos_light > 0)) return {direction, distance, Vec3<Real>(0), Real(0)};
        const Real density = choice.chance * distance_squared / (triangle.area * cos_light);
        return {direction, distance, radiance / density, density};
    }

private:
    struct Choice {
        std::size_t triangle = 0;
        Real reused = 0;  // where u fell within the triangle's share, again uniform in [0, 1)
        Real chance = 0;  // the probability of this triangle
    };
    using Weights = std::array<Real, weighed_by_view>;

    // What view_weights reads of the first weighed_by_view triangles, a column per coordinate,
    // unused slots zero (their area, so their weight, is zero), so that it weighs them all in
    // SIMD lanes (simd/pack.hpp). Triangle by triangle, each waiting on its square root and
    // division, the weights were a third of sample()'s time on the hw7 Cornell boxes.
    struct ViewTable {
        alignas(64) Weights ax{}, ay{}, az{};  // vertex a
        Weights e1x{}, e1y{}, e1z{};     // the edges from it
        Weights e2x{}, e2y{}, e2z{};
        Weights cx{}, cy{}, cz{};        // the centroid
        Weights anx{}, any{}, anz{};     // the normal times the area
        void add(std::size_t i, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& area_normal) {
            const glm::dvec3 centroid = (a + b + c) / 3.0;
            ax[i] = Real(a.x), ay[i] = Real(a.y), az[i] = Real(a.z);
            e1x[i] = Real(b.x - a.x), e1y[i] = Real(b.y - a.y), e1z[i] = Real(b.z - a.z);
            e2x[i] = Real(c.x - a.x), e2y[i] = Real(c.y - a.y), e2z[i] = Real(c.z - a.z);
            cx[i] = Real(centroid.x), cy[i] = Real(centroid.y), cz[i] = Real(centroid.z);
            anx[i] = Real(area_normal.x), any[i] = Real(area_normal.y), anz[i] = Real(area_normal.z);
        }
    };
    ViewTable view;

    // Each triangle's weight seen from `at` into `weights`, and their sum: A |cos| / d^3 at the
    // centroid, at most 2 pi (the bound of a solid angle: a triangle next to the point gets
    // most samples, but not all), zero where all three vertices are on or below the point's
    // tangent plane (then so is the whole triangle, which cannot light it). Positive wherever a
    // triangle can add light, so the estimate stays unbiased.
    Real view_weights(const ShadingFrame<Real>& at, Weights& weights) const {
        // One 32-byte register's lanes at a time (8 floats, 4 doubles). Not 64 bytes: a
        // 512-bit square root and division lower an Intel core's clock for everything after
        // them, and 32-byte lanes made hw7 path_diffuse and path_glass 0.90 and 0.89 of the
        // 64-byte lanes' time on the Intel VM, the same images (bench/RESULTS.md, "Path
        // tracer"). (Two 64-byte registers' square root also went through GCC's AVX-512
        // intrinsics, which warn falsely: GCC bug 105593.)
        constexpr int width = int(32 / sizeof(Real));
        static_assert(weighed_by_view % width == 0);
        using Lanes = simd::Pack<Real, width>;
        const Lanes px = Lanes::broadcast(at.position.x), py = Lanes::broadcast(at.position.y),
                    pz = Lanes::broadcast(at.position.z);
        const Lanes nx = Lanes::broadcast(at.normal.x), ny = Lanes::broadcast(at.normal.y),
                    nz = Lanes::broadcast(at.normal.z);
        const Lanes zero = Lanes::broadcast(0), bound = Lanes::broadcast(2 * pi<Real>);
        for (std::size_t first = 0; first < weighed_by_view; first += width) {
            const auto load = [first](const Weights& column) { return Lanes::load(column.data() + first); };
            const Lanes height = nx * (load(view.ax) - px) + ny * (load(view.ay) - py) + nz * (load(view.az) - pz);
            const Lanes rise1 = nx * load(view.e1x) + ny * load(view.e1y) + nz * load(view.e1z);
            const Lanes rise2 = nx * load(view.e2x) + ny * load(view.e2y) + nz * load(view.e2z);
            const Lanes highest = simd::max_keep(height, simd::max_keep(height + rise1, height + rise2));
            const Lanes x = load(view.cx) - px, y = load(view.cy) - py, z = load(view.cz) - pz;
            const Lanes distance_squared = x * x + y * y + z * z;
            const Lanes cosine = load(view.anx) * x + load(view.any) * y + load(view.anz) * z;
            const Lanes projected = simd::max_keep(cosine, -cosine);
            const Lanes looks = projected / (distance_squared * simd::sqrt(distance_squared));
            // Not (looks >= 0): a zero distance's NaN.
            select((highest > zero) & (looks >= zero), select(looks > bound, bound, looks), zero)
                .store(weights.data() + first);
        }
        Real total = 0;
        for (std::size_t i = 0; i < triangles.size(); ++i) total += weights[i];
        return total;
    }

    // The triangle for `u` (uniform in [0, 1)): through the view weights or by area.
    Choice choose(const ShadingFrame<Real>& at, Real u) const {
        const Real below_one = Real(1) - std::numeric_limits<Real>::epsilon();
        if (triangles.size() > weighed_by_view) {
            const auto chosen = by_area.sample(u);
            // The position of u within the chosen cell is again uniform: it places the point.
            const Real reused = std::clamp(chosen.x * Real(by_area.size()) - Real(chosen.cell), Real(0), below_one);
            return {chosen.cell, reused, triangles[chosen.cell].area / area};
        }
        Weights weights;
        const Real total = view_weights(at, weights);
        if (!(total > 0)) return {};
        Real x = u * total;
        std::size_t i = 0;
        for (; i + 1 < triangles.size() && !(x < weights[i]); ++i) x -= weights[i];
        while (weights[i] == 0) --i;  // rounding ran past the last weighed triangle
        return {i, std::clamp(x / weights[i], Real(0), below_one), weights[i] / total};
    }

    Real chance_of(const ShadingFrame<Real>& from, std::size_t triangle) const {
        if (triangles.size() > weighed_by_view) return triangles[triangle].area / area;
        Weights weights;
        const Real total = view_weights(from, weights);
        return total > 0 ? weights[triangle] / total : Real(0);
    }
};

}  // namespace prism
