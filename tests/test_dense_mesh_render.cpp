// The tiny-triangle dragon (dragon_lowres's dragon subdivided three times: 766,144 triangles at
// its original size, with the course file's mirror floor, camera and light) rendered with each
// triangle intersector, against a double-precision Watertight reference rendered with the same
// samples. Images are compared after the course's 8-bit conversion: a pixel differs when any
// channel is off by more than 1/255. The robust variants must match (at most 0.1% of pixels
// differ); the naive one's share is reported, and asserted to be large, because it exists to
// show the failure. A reduced resolution keeps the test short; the BVH builds dominate.
//
// The resolution is 240 x 240, not a quarter of the camera's 800 x 800: at 200 x 200 the centres
// of pixel row 122 lie exactly, in real arithmetic, on the far edge of the floor (z = -1, seen
// from y = 0.10 at distance 3), so float and double decide an exact tie along a whole row and
// 0.2% of the image differs for a reason that has nothing to do with the dragon.
#include "intersector_variants.hpp"

#include <prism/image/compare.hpp>
#include <prism/image/image_io.hpp>
#include <prism/io/load.hpp>
#include <prism/render/renderer.hpp>
#include <prism/scene/stress.hpp>

#include <doctest/doctest.h>

#include <filesystem>
#include <optional>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace {

namespace fs = std::filesystem;
using namespace prism_test;

const fs::path dragon_file = fs::path(PRISM_SHARED_DIR) / "ceng795/hw1/2020_ozgurcanc/assets/scenes/dragon_lowres.xml";
constexpr int subdivision_levels = 3;
constexpr int width = 240, height = 240;  // the camera's 800 x 800 at 0.3 (see above)

template <class Variant>
prism::Image render(const prism::scene::Scene& scene) {
    using Config = prism::Config<typename Variant::Real, prism::Bvh<typename Variant::Intersector>,
                                 prism::Lights<prism::PointLight>>;
    const prism::Renderer<Config> renderer(scene);
    return renderer.render(scene.cameras.at(0), width, height);
}

struct Dragon {
    prism::scene::Scene course;  // as the course file has it: 11,971 triangles
    prism::scene::Scene tiny;    // the same surface in 766,144 triangles
    std::vector<std::uint8_t> reference;  // the tiny dragon, Watertight double, 8-bit
};

// Loaded, subdivided and rendered once for every test case of this file; empty without the
// course data.
const std::optional<Dragon>& dragon() {
    static const std::optional<Dragon> dragon = []() -> std::optional<Dragon> {
        if (!fs::exists(dragon_file)) return std::nullopt;
        Dragon d{prism::io::load_scene(dragon_file), {}, {}};
        d.tiny = d.course;
        prism::scene::subdivide_largest_mesh(d.tiny, subdivision_levels);
        d.reference = prism::to_8bit(render<WatertightDouble>(d.tiny));
        return d;
    }();
    return dragon;
}

// Share (0..1) of pixels off by more than 1/255 from the reference.
template <class Variant>
double share_off(const Dragon& d) {
    return prism::share_off_by_more_than(prism::to_8bit(render<Variant>(d.tiny)), d.reference, 1);
}

}  // namespace

TEST_CASE_TEMPLATE("tiny-triangle dragon: robust intersectors render the double reference's image", Variant,
                   WatertightFloat, DoubleRefineFloat) {
    const auto& d = dragon();
    if (!d) {
        MESSAGE("skipped: " << dragon_file.string() << " not found (set PRISM_SHARED_DIR)");
        return;
    }
    REQUIRE(d->tiny.meshes.at(0).triangles.size() >= 750'000);
    const double share = share_off<Variant>(*d);
    MESSAGE((100.0 * share) << "% of pixels differ by more than 1/255 from Watertight double");
    CHECK(share <= 0.001);
}

// The reference itself is checked against an independent image: midpoint subdivision keeps every
// vertex on the original triangles, so the course's 11,971-triangle dragon is the same surface
// (flat shaded, so the same normals too).
TEST_CASE("tiny-triangle dragon: the double reference renders the course dragon's image") {
    const auto& d = dragon();
    if (!d) {
        MESSAGE("skipped: " << dragon_file.string() << " not found (set PRISM_SHARED_DIR)");
        return;
    }
    const double share =
        prism::share_off_by_more_than(prism::to_8bit(render<WatertightDouble>(d->course)), d->reference, 1);
    MESSAGE((100.0 * share) << "% of pixels differ by more than 1/255 between 11,971 and 766,144 triangles");
    CHECK(share <= 0.001);
}

TEST_CASE("tiny-triangle dragon: the naive epsilons lose it (reported)") {
    const auto& d = dragon();
    if (!d) {
        MESSAGE("skipped: " << dragon_file.string() << " not found (set PRISM_SHARED_DIR)");
        return;
    }
    const double share = share_off<NaiveFloat>(*d);
    MESSAGE("NaiveEpsilon float: " << (100.0 * share) << "% of pixels differ by more than 1/255 from Watertight double");
    // Every triangle of the tiny dragon fails the naive degenerate test (bench/RESULTS.md), so the
    // whole dragon and its mirror image are lost, not a few pixels.
    CHECK(share > 0.05);
}
