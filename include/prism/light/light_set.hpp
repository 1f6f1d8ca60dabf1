// A compile-time set of light types. `Lights<PointLight, SpotLight>` is the policy a Config
// names; `LightSet<Real, ...>` holds one vector per type and visits them with a fold
// expression, so a renderer compiled for point lights contains no code for any other light.
#pragma once

#include <prism/light/light_sample.hpp>

#include <cstddef>
#include <tuple>
#include <type_traits>
#include <vector>

namespace prism {

template <Scalar Real, template <class> class... LightTypes>
    requires(Light<LightTypes<Real>, Real> && ...)
class LightSet {
public:
    explicit LightSet(const scene::Scene& scene) : lights_(LightTypes<Real>::from_scene(scene)...) {}

    // Calls visit(light) for every light of every type.
    template <class Visit>
    void for_each(Visit&& visit) const {
        std::apply([&](const auto&... vectors) { (visit_all(vectors, visit), ...); }, lights_);
    }

    // The lights of one type, or nullptr when the set does not hold that type (so code for a
    // light type compiles away in sets without it).
    template <template <class> class Type>
    const std::vector<Type<Real>>* of_type() const {
        if constexpr ((std::is_same_v<Type<Real>, LightTypes<Real>> || ...))
            return &std::get<std::vector<Type<Real>>>(lights_);
        else
            return nullptr;
    }

    std::size_t size() const {
        return std::apply([](const auto&... vectors) { return (std::size_t(0) + ... + vectors.size()); }, lights_);
    }

private:
    template <class Vector, class Visit>
    static void visit_all(const Vector& lights, Visit& visit) {
        for (const auto& light : lights) visit(light);
    }

    std::tuple<std::vector<LightTypes<Real>>...> lights_;
};

template <template <class> class... LightTypes>
struct Lights {
    template <Scalar Real> using Set = LightSet<Real, LightTypes...>;

    // Whether the set holds light type `Type` (code for it is compiled in only then).
    template <template <class> class Type>
    static constexpr bool contains = (std::is_same_v<Type<float>, LightTypes<float>> || ...);

    // The light kinds this set can render; a Config covers a scene only if it has all of the
    // scene's, so that no light is silently dropped.
    static constexpr scene::LightKinds kinds = (scene::LightKinds(0) | ... | scene::bit(LightTypes<float>::kind));
};

}  // namespace prism
