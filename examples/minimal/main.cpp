// Include-and-go: build a scene in code, compose a renderer type from the parts it needs, render
// and write a PNG. No scene file format is involved.
#include <prism/image/image_io.hpp>
#include <prism/prism.hpp>

#include <iostream>

int main(int argc, char** argv) {
    namespace scene = prism::scene;
    scene::Scene world;
    world.ambient_light = {20, 20, 20};
    world.background_color = {10, 10, 30};
    world.max_recursion_depth = 4;

    scene::Camera camera;
    camera.position = {0, 1, 4};
    camera.gaze = {0, -0.2, -1};
    camera.near_left = -0.5;
    camera.near_right = 0.5;
    camera.near_bottom = -0.375;
    camera.near_top = 0.375;
    camera.width = 320;
    camera.height = 240;
    world.cameras.push_back(camera);
    world.point_lights.push_back({"key", {3, 5, 4}, {6000, 6000, 6000}});

    scene::Material matte;
    matte.ambient = {0.2, 0.2, 0.2};
    matte.diffuse = {0.7, 0.6, 0.5};
    matte.specular = {0.3, 0.3, 0.3};
    matte.phong_exponent = 32;
    scene::Material mirror = matte;
    mirror.type = scene::MaterialType::mirror;
    mirror.diffuse = {0.1, 0.1, 0.1};
    mirror.mirror = {0.8, 0.8, 0.8};
    world.materials = {matte, mirror};

    scene::Mesh floor;  // a quad of two triangles, counter-clockwise seen from above
    floor.positions = {{-4, 0, -4}, {-4, 0, 4}, {4, 0, 4}, {4, 0, -4}};
    floor.triangles = {{0, 1, 2}, {0, 2, 3}};
    world.meshes.push_back(floor);
    world.spheres.push_back({"left", 0, {-0.8, 0.6, 0}, 0.6});
    world.spheres.push_back({"right", 1, {0.8, 0.6, -0.5}, 0.6});

    // The renderer is a type: float precision, a BVH with watertight triangle tests, point lights.
    using Fast = prism::Config<float, prism::Bvh<prism::Watertight>, prism::Lights<prism::PointLight>>;
    const prism::Renderer<Fast> renderer(world);
    const prism::Image image = renderer.render(world.cameras[0]);

    const char* output = argc > 1 ? argv[1] : "minimal.png";
    prism::write_image(output, image);
    std::cout << "wrote " << output << " (" << image.width << "x" << image.height << ")\n";
    return 0;
}
