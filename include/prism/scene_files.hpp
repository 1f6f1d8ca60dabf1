// The umbrella include for the course's scene files: the loaders (XML and JSON of every schema
// year, PLY meshes) into the plain scene description, and render_scene, which chooses among the
// shipped renderers the one a scene needs and renders every camera (what the prism binary does).
#pragma once

#include <prism/io/load.hpp>
#include <prism/prism.hpp>
#include <prism/render/render_scene.hpp>
