// The <Lights> section of a scene file: AmbientLight, PointLight, DirectionalLight (its
// Direction is the way the light travels), SpotLight (full apex angles in degrees), AreaLight
// (the 2019+ square of a centre, a Normal and a Size, or the 2017-2018 corner and EdgeVectors)
// and SphericalDirectionalLight (an environment image).
#pragma once

#include <prism/io/element.hpp>
#include <prism/io/element_reader.hpp>
#include <prism/io/texture_loader.hpp>
#include <prism/io/transformation_loader.hpp>
#include <prism/math/transform.hpp>
#include <prism/scene/scene.hpp>

#include <glm/glm.hpp>

#include <string>
#include <utility>
#include <vector>

namespace prism::io::detail::scene_loader {

class LightLoader {
public:
    LightLoader(ElementReader& reader, scene::Scene& scene, const TransformationLoader& transformations,
                const TextureLoader& textures)
        : reader_(reader), scene_(scene), transformations_(transformations), textures_(textures) {}

    void read(const Element& section) {
        for (const Element& element : section.children) {
            if (element.name == "AmbientLight") {
                scene_.ambient_light = reader_.vector3(element);
            } else if (element.name == "PointLight") {
                scene::PointLight light;
                if (const std::string* id = element.attribute("id")) light.id = std::string(trim(*id));
                light.position = transform_point(transformations_.transformation_of(element),
                                                 reader_.vector3(reader_.required(element, "Position")));
                light.intensity = reader_.vector3(reader_.required(element, "Intensity"));
                reader_.note_unsupported_children(element, {"Position", "Intensity", "Transformations"});
                scene_.point_lights.push_back(std::move(light));
            } else if (element.name == "DirectionalLight") {
                scene::DirectionalLight light;
                light.id = reader_.id_of(element);
                const Element& direction = reader_.required(element, "Direction");
                light.direction =
                    transform_direction(transformations_.transformation_of(element), reader_.vector3(direction));
                if (glm::length(light.direction) == 0.0) reader_.fail(direction, "the direction is zero");
                light.radiance = reader_.vector3(reader_.required(element, "Radiance"));
                reader_.note_unsupported_children(element, {"Direction", "Radiance", "Transformations"});
                scene_.directional_lights.push_back(std::move(light));
            } else if (element.name == "SpotLight") {
                scene_.spot_lights.push_back(read_spot_light(element));
            } else if (element.name == "AreaLight") {
                scene_.area_lights.push_back(read_area_light(element));
            } else if (element.name == "SphericalDirectionalLight") {
                scene_.environment_lights.push_back(read_environment_light(element));
            } else {
                reader_.note_unsupported(element);
            }
        }
    }

private:
    // Angles are the full apex angles of the cones, in degrees (light/spot_light.hpp).
    scene::SpotLight read_spot_light(const Element& element) {
        scene::SpotLight light;
        light.id = reader_.id_of(element);
        const glm::dmat4 transform = transformations_.transformation_of(element);
        light.position = transform_point(transform, reader_.vector3(reader_.required(element, "Position")));
        const Element& direction = reader_.required(element, "Direction");
        light.direction = transform_direction(transform, reader_.vector3(direction));
        if (glm::length(light.direction) == 0.0) reader_.fail(direction, "the direction is zero");
        light.intensity = reader_.vector3(reader_.required(element, "Intensity"));
        const Element& coverage = reader_.required(element, "CoverageAngle");
        light.coverage_angle = reader_.number(coverage);
        if (!(light.coverage_angle > 0.0 && light.coverage_angle <= 360.0))
            reader_.fail(coverage, "the coverage angle (the cone's full apex angle, in degrees) must be in (0, 360]");
        const Element& falloff = reader_.required(element, "FalloffAngle");
        light.falloff_angle = reader_.number(falloff);
        if (!(light.falloff_angle >= 0.0 && light.falloff_angle <= light.coverage_angle))
            reader_.fail(falloff, "the falloff angle must be between 0 and the coverage angle (" +
                                      std::to_string(light.coverage_angle) + " degrees)");
        reader_.note_unsupported_children(element, {"Position", "Direction", "Intensity", "CoverageAngle", "FalloffAngle",
                                                    "Transformations"});
        return light;
    }

    // Two forms. 2019+: Position is the centre of a square of side Size facing Normal, Radiance
    // its radiance; the square's edges are the course's orthonormal pair for a direction n (the
    // one its glossy reflections use): u = normalize(h x n), with h = n whose smallest-magnitude
    // component is set to 1, and v = n x u; so edge1 x edge2 points along Normal, and a normal
    // along an axis gives axis-aligned edges (0 -1 0: edge1 along -z, edge2 along +x).
    // 2017-2018: Position is a corner, EdgeVector1 and EdgeVector2 the edges, Intensity the
    // radiance (scene.hpp). Transformations, if any, move the corner and the edges.
    scene::AreaLight read_area_light(const Element& element) {
        scene::AreaLight light;
        light.id = reader_.id_of(element);
        const scene::Vec3 position = reader_.vector3(reader_.required(element, "Position"));
        if (element.child("EdgeVector1") != nullptr || element.child("EdgeVector2") != nullptr) {
            light.corner = position;
            light.edge1 = reader_.vector3(reader_.required(element, "EdgeVector1"));
            light.edge2 = reader_.vector3(reader_.required(element, "EdgeVector2"));
        } else {
            const Element& normal_element = reader_.required(element, "Normal");
            const scene::Vec3 normal = reader_.vector3(normal_element);
            if (glm::length(normal) == 0.0) reader_.fail(normal_element, "the normal is zero");
            const double size = reader_.positive(reader_.required(element, "Size"));
            const scene::Vec3 n = glm::normalize(normal);
            scene::Vec3 helper = n;
            const scene::Vec3 magnitude = glm::abs(n);
            if (magnitude.x <= magnitude.y && magnitude.x <= magnitude.z) helper.x = 1.0;
            else if (magnitude.y <= magnitude.z) helper.y = 1.0;
            else helper.z = 1.0;
            const scene::Vec3 u = glm::normalize(glm::cross(helper, n));
            const scene::Vec3 v = glm::cross(n, u);
            light.edge1 = size * u;
            light.edge2 = size * v;
            light.corner = position - 0.5 * (light.edge1 + light.edge2);
        }
        const Element* radiance = element.child("Radiance");
        const Element* intensity = radiance == nullptr ? element.child("Intensity") : nullptr;
        if (radiance == nullptr && intensity == nullptr)
            reader_.fail(element, "missing <Radiance> (before 2019: <Intensity>)");
        const glm::dmat4 transform = transformations_.transformation_of(element);
        light.corner = transform_point(transform, light.corner);
        light.edge1 = transform_direction(transform, light.edge1);
        light.edge2 = transform_direction(transform, light.edge2);
        const double area = glm::length(glm::cross(light.edge1, light.edge2));
        if (area == 0.0) reader_.fail(element, "the light's edges span no area");
        // Before 2019 the panel had an Intensity, the whole panel's, as a point light has one:
        // each sample lights a point by I |cos theta_l| / d^2 (a 2018 course renderer,
        // emrebarisc/AdvancedRayTracing), which is radiance I / A. The 2017 glass_plates_area is
        // glass_plates_point with its point light turned into a 5 x 5 panel of the same
        // Intensity; read as radiance, such scenes come out 25 to 100 times too bright.
        light.radiance = radiance != nullptr ? reader_.vector3(*radiance) : reader_.vector3(*intensity) / area;
        reader_.note_unsupported_children(element, {"Position", "Normal", "Size", "Radiance", "EdgeVector1", "EdgeVector2",
                                                    "Intensity", "Transformations"});
        return light;
    }

    // <SphericalDirectionalLight type="latlong|probe"><ImageId/><Sampler/>: an image of
    // <Textures><Images> around the scene; Sampler uniform|cosine (default, as the course) or
    // importance; Scale (1 or 3 numbers) multiplies the image's radiance.
    scene::EnvironmentLight read_environment_light(const Element& element) {
        scene::EnvironmentLight light;
        light.id = reader_.id_of(element);
        light.image = textures_.image_of(reader_.required(element, "ImageId"));
        if (const std::string* type = element.attribute("type")) {
            using enum scene::EnvironmentLayout;
            light.layout = reader_.keyword<scene::EnvironmentLayout>(element, "environment layout", *type,
                                                                     {{"latlong", latlong}, {"probe", probe}});
        }
        if (const Element* e = element.child("Sampler")) {
            using enum scene::EnvironmentSampling;
            light.sampling = reader_.keyword<scene::EnvironmentSampling>(
                *e, "sampler", {{"uniform", uniform}, {"cosine", cosine}, {"importance", importance}});
        }
        if (const Element* e = element.child("Scale")) {
            const std::vector<double> v = reader_.numbers(*e);
            if (v.size() == 1) light.scale = scene::Vec3(v[0]);
            else if (v.size() == 3) light.scale = {v[0], v[1], v[2]};
            else reader_.fail(*e, "expected 1 or 3 numbers, found " + std::to_string(v.size()));
            if (glm::any(glm::lessThan(light.scale, scene::Vec3(0.0)))) reader_.fail(*e, "must not be negative");
        }
        reader_.note_unsupported_children(element, {"ImageId", "Sampler", "Scale"});
        return light;
    }

    ElementReader& reader_;
    scene::Scene& scene_;
    const TransformationLoader& transformations_;
    const TextureLoader& textures_;
};

}  // namespace prism::io::detail::scene_loader
