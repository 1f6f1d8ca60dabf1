// Environment maps made from a formula instead of a photograph: a simple sky (a vertical gradient
// from the horizon's colour to the zenith's, a flat ground colour below the horizon, and a sun
// disc of given direction, angular diameter and radiance) and a constant environment. Written in
// either of the course's layouts (light/environment_map.hpp), so the same sky can be compared
// across layouts, and a constant map makes a white furnace. `prism-envmap` writes them to EXR.
#pragma once

#include <prism/image/image.hpp>
#include <prism/light/environment_map.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace prism {

struct ProceduralSky {
    glm::dvec3 horizon{0.9, 0.95, 1.0};
    glm::dvec3 zenith{0.25, 0.45, 0.9};
    glm::dvec3 ground{0.3, 0.27, 0.25};
    glm::dvec3 sun_direction{0.0, 1.0, 0.0};  // towards the sun; need not be unit
    double sun_angle_degrees = 0.53;          // the disc's full apparent diameter (the Sun's: 0.53)
    glm::dvec3 sun_radiance{0.0};             // zero: no sun

    // The radiance arriving from unit `direction`. Above the horizon the colour moves from the
    // horizon's to the zenith's linearly in elevation angle.
    glm::dvec3 radiance(const glm::dvec3& direction) const {
        if (sun_radiance != glm::dvec3(0.0) && glm::length(sun_direction) > 0) {
            const double cos_to_sun = glm::dot(direction, glm::normalize(sun_direction));
            const double half_angle = sun_angle_degrees / 2 * pi<double> / 180;
            if (cos_to_sun >= std::cos(half_angle)) return sun_radiance;
        }
        if (direction.y < 0) return ground;
        const double elevation = std::asin(std::clamp(direction.y, 0.0, 1.0)) / (pi<double> / 2);
        return horizon + (zenith - horizon) * elevation;
    }
};

// The image size of a layout at a given width: lat-long maps are twice as wide as tall (2 pi of
// azimuth by pi of polar angle, square pixels), probes are square.
inline int environment_height(scene::EnvironmentLayout layout, int width) {
    return layout == scene::EnvironmentLayout::latlong ? std::max(width / 2, 1) : width;
}

// An environment image of `width` pixels across holding radiance(direction) in `layout`. Each
// pixel averages samples x samples directions spread over it, so the sun's edge is antialiased
// the same way in both layouts; probe pixels average over the part inside the disc with zero
// outside it, as the probe files do (black outside the disc).
template <class RadianceOfDirection>
Image render_environment(const RadianceOfDirection& radiance, scene::EnvironmentLayout layout, int width, int samples = 4) {
    if (width < 2) throw std::invalid_argument("an environment map needs a width of at least 2 pixels");
    samples = std::max(samples, 1);
    Image image(width, environment_height(layout, width));
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            glm::dvec3 sum(0.0);
            for (int sy = 0; sy < samples; ++sy)
                for (int sx = 0; sx < samples; ++sx) {
                    const glm::dvec2 uv((x + (sx + 0.5) / samples) / image.width, (y + (sy + 0.5) / samples) / image.height);
                    if (layout == scene::EnvironmentLayout::probe) {
                        const glm::dvec2 centred(2 * uv.x - 1, 1 - 2 * uv.y);
                        if (glm::dot(centred, centred) > 1) continue;
                        sum += radiance(probe_direction(uv));
                    } else {
                        sum += radiance(latlong_direction(uv));
                    }
                }
            image(x, y) = glm::vec3(sum / double(samples * samples));
        }
    return image;
}

inline Image render_sky(const ProceduralSky& sky, scene::EnvironmentLayout layout, int width, int samples = 4) {
    return render_environment([&](const glm::dvec3& direction) { return sky.radiance(direction); }, layout, width,
                              samples);
}

inline Image render_constant(const glm::dvec3& radiance, scene::EnvironmentLayout layout, int width, int samples = 4) {
    return render_environment([&](const glm::dvec3&) { return radiance; }, layout, width, samples);
}

}  // namespace prism
