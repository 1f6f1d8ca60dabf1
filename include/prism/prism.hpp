// The umbrella include for composing renderers: the plain scene description, the policies a
// Config is made of (precision, accelerators and triangle tests, lights, integrators), the
// Renderer, and images in and out. Reading scene files is <prism/scene_files.hpp>: the loaders
// parse JSON and XML libraries that a scene built in code never needs (examples/minimal: 190 MB
// and a quarter of its parse time, bench/RESULTS.md "Compile cost").
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
#include <prism/light/directional_light.hpp>
#include <prism/light/light_set.hpp>
#include <prism/light/point_light.hpp>
#include <prism/light/spot_light.hpp>
#include <prism/render/config.hpp>
#include <prism/render/renderer.hpp>
#include <prism/scene/features.hpp>
#include <prism/scene/scene.hpp>
