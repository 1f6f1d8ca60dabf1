// The umbrella include: the whole toolkit, from the plain scene description to the renderer.
#pragma once

#include <prism/accel/accelerator.hpp>
#include <prism/camera/pinhole_camera.hpp>
#include <prism/geometry/double_refine.hpp>
#include <prism/geometry/naive_epsilon.hpp>
#include <prism/geometry/scene_geometry.hpp>
#include <prism/geometry/subdivide.hpp>
#include <prism/geometry/surface_error.hpp>
#include <prism/geometry/watertight.hpp>
#include <prism/image/compare.hpp>
#include <prism/image/image.hpp>
#include <prism/image/image_io.hpp>
#include <prism/image/tonemap.hpp>
#include <prism/io/load.hpp>
#include <prism/light/directional_light.hpp>
#include <prism/light/light_set.hpp>
#include <prism/light/point_light.hpp>
#include <prism/light/spot_light.hpp>
#include <prism/render/config.hpp>
#include <prism/render/render_scene.hpp>
#include <prism/render/renderer.hpp>
#include <prism/scene/features.hpp>
#include <prism/scene/scene.hpp>
