// The path tracer: a furnace with an analytic answer under every RendererParams combination,
// every combination converging to the same image within its noise, images identical at any
// thread count, and dispatch: the path tracer only for scenes with a path-traced camera.
#include "one_by_one_pixel.hpp"
#include "temporary_folder.hpp"

#include <prism/io/load.hpp>
#include <prism/math/denormals.hpp>
#include <prism/render/path_tracer.hpp>
#include <prism/render/render_scene.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace {

namespace scene = prism::scene;
using prism_test::TemporaryFolder;

// The shipped renderers' wide BVH, whose camera rays go side by side through the index: one
// renderer type per precision for every test here (each more costs minutes of CI's builds).
template <class Real>
using PathConfig = prism::Config<Real, prism::WideBvh<prism::Watertight, 8>, prism::AllLightSet, prism::all_features,
                                 prism::PathTracer, prism::ChosenPattern>;

// Every combination of the course's three words, and MIS (which implies next-event estimation).
std::vector<scene::RendererParams> all_params() {
    std::vector<scene::RendererParams> list;
    for (int bits = 0; bits < 8; ++bits)
        list.push_back({true, (bits & 1) != 0, (bits & 2) != 0, (bits & 4) != 0, false});
    list.push_back({true, true, true, false, true});
    list.push_back({true, true, false, true, true});
    return list;
}

constexpr std::array samplers{prism::SamplerKind::independent, prism::SamplerKind::stratified, prism::SamplerKind::sobol};

// The samplers the statistical tests (furnace, agreement) run in precision Real: every sampler in
// float, independent samples alone in double. Whether an estimator converges to the right image
// depends on the sampler's numbers, not on the precision the path is traced in, which the
// independent runs and the bit-for-bit tests below cover in both; the stratified and sobol runs
// in double cost CI's sanitized build a minute.
template <class Real>
std::vector<prism::SamplerKind> statistical_samplers() {
    if constexpr (std::is_same_v<Real, float>) return {samplers.begin(), samplers.end()};
    else return {prism::SamplerKind::independent};
}

std::string describe(const scene::RendererParams& p) {
    std::ostringstream out;
    out << (p.next_event_estimation ? "NEE " : "") << (p.importance_sampling ? "IS " : "")
        << (p.russian_roulette ? "RR " : "") << (p.multiple_importance ? "MIS" : "");
    return out.str();
}

scene::Camera camera_at(const glm::dvec3& position, const glm::dvec3& gaze, int size, int samples) {
    scene::Camera camera;
    camera.position = position;
    camera.gaze = gaze;
    camera.up = {0, 1, 0};
    camera.near_left = camera.near_bottom = -0.5;
    camera.near_right = camera.near_top = 0.5;
    camera.width = camera.height = size;
    camera.num_samples = samples;
    camera.image_name = "out.exr";
    return camera;
}

// A closed cube (side 2, centred at the origin) that emits Le = 1 everywhere and reflects
// diffusely with albedo rho = 1/2 (a normalised ModifiedPhong with ks = 0: kd / pi). Every point sees the same
// radiance, so L = Le (1 + rho + ... + rho^D) after at most D bounces: 1.875 for D = 3.
scene::Scene furnace() {
    scene::Scene world;
    world.max_recursion_depth = 3;
    scene::Material material;
    material.diffuse = {0.5, 0.5, 0.5};
    material.brdf = scene::Brdf{"1", scene::BrdfModel::modified_phong, 10.0, true, false};
    world.materials.push_back(material);
    scene::Mesh cube;
    for (int i = 0; i < 8; ++i) cube.positions.push_back({i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1});
    cube.triangles = {{0, 1, 3}, {0, 3, 2}, {4, 7, 5}, {4, 6, 7}, {0, 4, 5}, {0, 5, 1},
                      {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
    cube.radiance = {1, 1, 1};
    world.meshes.push_back(cube);
    world.cameras.push_back(camera_at({0.1, 0.2, 0.3}, {0.3, -0.2, -1}, 8, 1024));
    return world;
}

double mean_of(const prism::Image& image) {
    double sum = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) sum += (image(x, y).r + image(x, y).g + image(x, y).b) / 3.0;
    return sum / (image.width * image.height);
}

// A small Cornell box: white floor, back wall and ceiling, a red left and a green right wall
// (normalised diffuse), a glossy sphere (normalised ModifiedBlinnPhong), a LightMesh square below the ceiling and a small LightSphere; a point light
// too, which only next-event estimation can see, so it is left out here (all combinations must
// estimate the same image).
const char* const cornell_xml = R"(<Scene>
    <MaxRecursionDepth>3</MaxRecursionDepth>
    <Cameras><Camera id="1">
        <Position>0 0 3.5</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
        <NearPlane>-0.5 0.5 -0.5 0.5</NearPlane><NearDistance>1.2</NearDistance>
        <ImageResolution>8 8</ImageResolution><ImageName>out.exr</ImageName>
        <NumSamples>256</NumSamples>
        <Renderer>PathTracing</Renderer>
    </Camera></Cameras>
    <BRDFs>
        <ModifiedPhong id="1" normalized="true"><Exponent>1</Exponent></ModifiedPhong>
        <ModifiedBlinnPhong id="2" normalized="true"><Exponent>20</Exponent></ModifiedBlinnPhong>
    </BRDFs>
    <Materials>
        <Material id="1" BRDF="1"><DiffuseReflectance>0.8 0.8 0.8</DiffuseReflectance></Material>
        <Material id="2" BRDF="1"><DiffuseReflectance>0.8 0.2 0.2</DiffuseReflectance></Material>
        <Material id="3" BRDF="1"><DiffuseReflectance>0.2 0.8 0.2</DiffuseReflectance></Material>
        <Material id="4" BRDF="2"><DiffuseReflectance>0.5 0.5 0.5</DiffuseReflectance>
            <SpecularReflectance>0.3 0.3 0.3</SpecularReflectance></Material>
        <Material id="5"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material>
    </Materials>
    <VertexData>
        -1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1
        -1 -1 1   1 -1 1   1 1 1   -1 1 1
        -0.3 0.98 -0.3  0.3 0.98 -0.3  0.3 0.98 0.3  -0.3 0.98 0.3
        0.4 -0.6 -0.2  -0.5 0.5 0.2
    </VertexData>
    <Objects>
        <Mesh id="1"><Material>1</Material><Faces>1 2 6 1 6 5  1 4 3 1 3 2  4 8 7 4 7 3</Faces></Mesh>
        <Mesh id="2"><Material>2</Material><Faces>1 5 8 1 8 4</Faces></Mesh>
        <Mesh id="3"><Material>3</Material><Faces>2 3 7 2 7 6</Faces></Mesh>
        <LightMesh id="4"><Material>5</Material><Radiance>6 6 6</Radiance><Faces>9 11 10 9 12 11</Faces></LightMesh>
        <Sphere id="5"><Material>4</Material><Center>13</Center><Radius>0.4</Radius></Sphere>
        <LightSphere id="6"><Material>5</Material><Center>14</Center><Radius>0.08</Radius>
            <Radiance>40 30 20</Radiance></LightSphere>
    </Objects>
</Scene>)";

}  // namespace

TEST_CASE_TEMPLATE("PathTracer: a furnace renders its analytic radiance under every RendererParams and sampler",
                   Real, float, double) {
    // The furnace's 64 pixels all estimate the same radiance, so their spread is the estimate's
    // noise: the analytic value must lie within 4.5 standard errors of the image's mean, and the
    // standard error must be below 2% for that to say something. (A fixed 1% held for seed 0 by
    // luck under next-event estimation, whose samples of the light a point lies on have a heavy
    // tail: independent NEE RR gave 1.854-1.911 over seeds 0-5, standard errors 0.4-1.7%. Without
    // NEE, 4.5 standard errors are 0.1-0.5%.)
    const auto check_furnace = [](const prism::Image& image) {
        double sum = 0, squares = 0;
        const double n = double(image.width) * image.height;
        for (const glm::vec3& pixel : image.pixels) {
            const double value = (pixel.r + pixel.g + pixel.b) / 3.0;
            sum += value;
            squares += value * value;
        }
        const double mean = sum / n;
        const double error = std::sqrt(std::max(0.0, squares / n - mean * mean) / (n - 1));
        CAPTURE(mean);
        CAPTURE(error);
        CHECK(error < 0.02 * 1.875);
        CHECK(std::abs(mean - 1.875) <= 4.5 * error);
    };
    scene::Scene world = furnace();
    for (const prism::SamplerKind kind : statistical_samplers<Real>()) {
        CAPTURE(prism::sampler_name(kind));
        prism::RendererSettings settings;
        settings.backface_culling = prism::BackfaceCulling::none;  // the camera is inside the cube
        settings.sampler = kind;
        const prism::Renderer<PathConfig<Real>> renderer(world, settings);
        for (const scene::RendererParams& params : all_params()) {
            CAPTURE(describe(params));
            scene::Camera camera = world.cameras[0];
            camera.renderer = params;
            check_furnace(renderer.render(camera));
        }
    }
    const prism::RendererSettings settings{prism::BackfaceCulling::none, prism::RayOffset::scene_epsilon, 0, {}};
    const prism::Renderer<PathConfig<Real>> renderer(world, settings);
    // Without path tracing, the ray tracer sees the emission and one bounce of direct light.
    scene::Camera traced = world.cameras[0];
    CHECK(mean_of(renderer.render(traced)) != doctest::Approx(1.875).epsilon(0.01));
}

TEST_CASE_TEMPLATE("PathTracer: every RendererParams combination converges to the same image, within its noise", Real,
                   float, double) {
    TemporaryFolder folder;
    const scene::Scene world = prism::io::load_scene(folder.write("cornell.xml", cornell_xml));
    // Each combination renders 4 independent images (seeds); the mean and its standard error per
    // 4 x 4 block of pixels and channel are compared with the reference combination's
    // (NEE + IS, the lowest noise): within 4.5 combined standard errors. A block's variance is
    // the sum of its 16 pixels' (independent estimates), each estimated from the 4 seeds: 48
    // degrees of freedom rather than the 3 of the block's own spread over the seeds, whose
    // Student tail fails 4.5 estimated errors in about one check in 50 by chance alone.
    const int seeds = 4;
    struct Estimate {
        std::vector<double> mean, error;
    };
    const auto estimate = [&](const scene::RendererParams& params, prism::SamplerKind kind) {
        std::vector<double> sum(8 * 8 * 3, 0.0), squares(8 * 8 * 3, 0.0);  // per pixel and channel
        for (int s = 0; s < seeds; ++s) {
            prism::RendererSettings settings;
            settings.backface_culling = prism::BackfaceCulling::none;  // the box's walls face either way
            settings.seed = std::uint64_t(s + 1);
            settings.sampler = kind;
            const prism::Renderer<PathConfig<Real>> renderer(world, settings);
            scene::Camera camera = world.cameras[0];
            camera.renderer = params;
            const prism::Image image = renderer.render(camera);
            for (int y = 0; y < 8; ++y)
                for (int x = 0; x < 8; ++x)
                    for (int c = 0; c < 3; ++c) {
                        const double value = image(x, y)[c];
                        sum[std::size_t((y * 8 + x) * 3 + c)] += value;
                        squares[std::size_t((y * 8 + x) * 3 + c)] += value * value;
                    }
        }
        // Per block and channel: the mean of its pixels' means, and the variance of that mean,
        // the sum of its pixels' variances of their means over 16^2.
        Estimate result{std::vector<double>(12, 0.0), std::vector<double>(12, 0.0)};
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x)
                for (int c = 0; c < 3; ++c) {
                    const std::size_t p = std::size_t((y * 8 + x) * 3 + c), b = std::size_t(((y / 4) * 2 + x / 4) * 3 + c);
                    const double mean = sum[p] / seeds;
                    const double variance = std::max(0.0, (squares[p] - seeds * mean * mean) / (seeds - 1));
                    result.mean[b] += mean / 16;
                    result.error[b] += variance / seeds / (16.0 * 16.0);
                }
        for (double& error : result.error) error = std::sqrt(error);
        return result;
    };
    // Every sampler's estimate of every combination against the independent one of the reference
    // combination: the samplers change the noise, not the image.
    const Estimate reference = estimate({true, true, true, false, false}, prism::SamplerKind::independent);
    for (const prism::SamplerKind kind : statistical_samplers<Real>()) {
        for (const scene::RendererParams& params : all_params()) {
            CAPTURE(prism::sampler_name(kind));
            CAPTURE(describe(params));
            const Estimate other = estimate(params, kind);
            for (int b = 0; b < 12; ++b) {
                CAPTURE(b);
                CAPTURE(reference.mean[b]);
                CAPTURE(other.mean[b]);
                CHECK(reference.mean[b] > 0.01);
                const double noise = std::sqrt(reference.error[b] * reference.error[b] + other.error[b] * other.error[b]);
                CHECK(std::abs(other.mean[b] - reference.mean[b]) <= 4.5 * noise + 1e-6);
            }
        }
    }
}

TEST_CASE_TEMPLATE("PathTracer: camera rays through the batch entries give each pixel the one-by-one trace's bits",
                   Real, float, double) {
    // Renderer hands camera rays to the integrator several at a time: their closest hits first
    // (camera_hits), then each path from its hit (radiance_row for a row of one-sample pixels,
    // radiance_at and radiances_at for a pixel's samples). The reference is the integrator's own
    // radiance, ray by ray on each pixel's stream, summed with the filter weights as the
    // Renderer sums them: every pixel's bits must agree, for path-traced cameras under several
    // RendererParams and for a ray-traced camera in the same renderer. The Renderer batches the
    // ray-traced camera's rays only (PathTracerIntegrator::batches_camera_rays), so the batch
    // entries are also called here as the Renderer calls them, for every camera: a row of
    // one-sample pixels through radiance_row, a pixel's samples through radiances_at. The wide
    // BVH batches the hits (intersect_each through the index of the box and a 128-triangle
    // ridged floor).
    TemporaryFolder folder;
    scene::Scene world = prism::io::load_scene(folder.write("cornell.xml", cornell_xml));
    world.point_lights.push_back({"bulb", {0.2, 0.6, 0.3}, {2, 2, 2}});
    scene::Mesh ridges;
    ridges.material = 0;
    constexpr int cells = 8;
    for (int z = 0; z <= cells; ++z)
        for (int x = 0; x <= cells; ++x)
            ridges.positions.push_back({-0.9 + 1.8 * x / cells, -0.95 + 0.04 * ((x + z) % 2), -0.9 + 1.8 * z / cells});
    for (int z = 0; z < cells; ++z)
        for (int x = 0; x < cells; ++x) {
            const std::uint32_t a = std::uint32_t(z * (cells + 1) + x), b = a + 1, c = a + cells + 1, d = c + 1;
            ridges.triangles.push_back({a, c, b});
            ridges.triangles.push_back({b, c, d});
        }
    world.meshes.push_back(ridges);
    using Whole = prism::Renderer<PathConfig<Real>>;
    // Every sampler's image against the one-by-one trace (a sampler that is not a stream gives
    // each sample its own dimensions, so the Renderer starts each sample's path where
    // one_by_one_pixel does); the batch entries as the Renderer calls them for a stream.
    for (const prism::SamplerKind kind : samplers) {
        CAPTURE(prism::sampler_name(kind));
        const prism::RendererSettings settings{prism::BackfaceCulling::triangles, prism::RayOffset::scene_epsilon, 3, kind};
        const Whole renderer(world, settings);
        const prism_test::RendererParts<Whole> parts(world, settings);
        const auto& integrator = parts.integrator;
        using Path = typename Whole::Integrator::CameraPath;
        using Sampler = typename Whole::PixelSamplerT;
        std::vector<scene::RendererParams> cameras = {{true, true, true, true, true}, {true, false, false, false, false},
                                                      {true, true, false, true, false}, {}};
        for (const scene::RendererParams& params : cameras) {
            double total = 0;  // over the camera's images: not all black (one sample without NEE may be)
            for (const int count : {1, 5, 40}) {
                CAPTURE(describe(params));
                CAPTURE(params.path_tracing);
                CAPTURE(count);
                scene::Camera camera = world.cameras[0];
                camera.width = camera.height = 12;
                camera.renderer = params;
                camera.num_samples = count;
                const prism::Image image = renderer.render(camera);
                const prism::ThinLensCamera<Real> lens(camera, camera.width, camera.height);
                const auto pattern = prism::make_pattern<typename Whole::Pattern>(
                    {count, camera.width, camera.height, settings.seed, settings.sampler});
                const auto uv = [&](int x, int y) {
                    return prism::Vec2<Real>((Real(x) + Real(0.5)) / Real(camera.width),
                                             (Real(y) + Real(0.5)) / Real(camera.height));
                };
                // Pixel (x, y) through the batch entries: a row of one-sample pixels (radiance_row),
                // or the pixel's samples' hits, then radiances_at in chunks of prelit_width.
                std::vector<prism::CameraSample<Real>> samples;
                std::vector<prism::Vec2<Real>> strata;
                std::vector<glm::vec3> row(std::size_t(camera.width));
                const auto batched_row = [&](int y) {
                    std::vector<Sampler> streams;
                    std::vector<prism::Ray<Real>> rays;
                    for (int x = 0; x < camera.width; ++x) {
                        prism::Random random = prism::Random::for_pixel(x, y, settings.seed);
                        const prism::CameraSample<Real> sample = prism::centre_sample<Real>(random);
                        streams.emplace_back(prism::IndependentSampler(random));
                        rays.push_back(lens.ray(Real(x) + sample.pixel.x, Real(y) + sample.pixel.y, sample.lens, sample.time));
                    }
                    std::vector<prism::Hit<Real>> hits(rays.size());
                    const std::uint32_t found = integrator.camera_hits(rays.data(), hits.data(), camera.width);
                    std::vector<prism::Vec3<Real>> radiance(rays.size());
                    integrator.radiance_row(rays.data(), hits.data(), found, camera.width,
                                            [&](int x) { return Path{streams[std::size_t(x)], uv(x, y), lens.pixel_spread(), params}; },
                                            radiance.data());
                    for (int x = 0; x < camera.width; ++x) row[std::size_t(x)] = glm::vec3(prism::Vec3<Real>(0) + radiance[std::size_t(x)]);
                };
                const auto batched_pixel = [&](int x, int y) {
                    prism::Random random = prism::Random::for_pixel(x, y, settings.seed);
                    prism::camera_samples(count, random, samples, strata);
                    Sampler sampler(prism::IndependentSampler{random});
                    Path path{sampler, uv(x, y), lens.pixel_spread(), params};
                    std::vector<prism::Ray<Real>> rays;
                    for (const prism::CameraSample<Real>& sample : samples)
                        rays.push_back(lens.ray(Real(x) + sample.pixel.x, Real(y) + sample.pixel.y, sample.lens, sample.time));
                    std::vector<prism::Hit<Real>> hits(rays.size());
                    prism::Vec3<Real> sum(0);
                    Real weights = 0;
                    const int width = Whole::Integrator::prelit_width;
                    for (int part = 0; part < count; part += width) {
                        const int n = std::min(width, count - part);
                        const std::uint32_t found = integrator.camera_hits(rays.data() + part, hits.data() + part, n);
                        std::vector<prism::Vec3<Real>> radiance(static_cast<std::size_t>(n));
                        integrator.radiances_at(rays.data() + part, hits.data() + part, found, n, path, [](int) {},
                                                radiance.data());
                        for (int i = 0; i < n; ++i) {
                            const Real weight = prism::filter_weight(camera.filter, samples[std::size_t(part + i)].pixel);
                            sum += weight * radiance[std::size_t(i)];
                            weights += weight;
                        }
                    }
                    return glm::vec3(sum / weights);
                };
                int mismatches = 0, batch_mismatches = 0;
                for (int y = 0; y < camera.height; ++y) {
                    if (count == 1) batched_row(y);
                    for (int x = 0; x < camera.width; ++x) {
                        const glm::vec3 expected = prism_test::one_by_one_pixel(
                            integrator, lens, camera, pattern, count, x, y, settings.seed,
                            [&](Sampler& sampler, const prism::Vec2<Real>& pixel_uv, Real spread) {
                                return Path{sampler, pixel_uv, spread, params};
                            });
                        mismatches += std::memcmp(&expected, &image(x, y), sizeof expected) != 0;
                        total += expected.r + expected.g + expected.b;
                        if (kind != prism::SamplerKind::independent) continue;
                        const glm::vec3 batched = count == 1 ? row[std::size_t(x)] : batched_pixel(x, y);
                        batch_mismatches += std::memcmp(&expected, &batched, sizeof expected) != 0;
                    }
                }
                CHECK(mismatches == 0);
                CHECK(batch_mismatches == 0);
            }
            CHECK(total > 0);
        }
    }
}

TEST_CASE("PathTracer: the same seed gives the same image at 1 and 2 threads, with every sampler") {
    // 40 x 40 pixels are 9 tiles of 16 x 16, so two threads split them.
    TemporaryFolder folder;
    scene::Scene world = prism::io::load_scene(folder.write("cornell.xml", cornell_xml));
    world.cameras[0].num_samples = 6;
    world.cameras[0].width = world.cameras[0].height = 40;
    world.cameras[0].renderer = {true, true, true, true, true};
    for (const prism::SamplerKind kind : samplers) {
        CAPTURE(prism::sampler_name(kind));
        std::ostringstream log;
        prism::RenderOptions one;
        one.threads = 1;
        one.backface_culling = prism::BackfaceCulling::none;
        one.sampler = kind;
        prism::RenderOptions two = one;
        two.threads = 2;
        const auto first = prism::render_scene(world, one, log);
        const auto second = prism::render_scene(world, two, log);
        REQUIRE(first.size() == 1);
        CHECK(first[0].image.pixels == second[0].image.pixels);
        CHECK(log.str().find("path tracing") != std::string::npos);
    }
}

TEST_CASE_TEMPLATE("Renderer: tiles flush subnormals to zero, and the caller's floating-point mode holds in on_tile and after",
                   Real, float, double) {
    // math/denormals.hpp: GCC's 4-lane Vec3 arithmetic reads a stack word as its fourth lane,
    // and a subnormal there costs an Intel core a microcode assist per multiplication. The
    // render's tiles set DAZ and FTZ; the consumer's code (on_tile, and after render) must not.
    const auto flushes = [] {
        volatile Real tiny = std::numeric_limits<Real>::min() / 4;  // subnormal
        const Real product = tiny * Real(1);
        return product == 0;
    };
    REQUIRE_FALSE(flushes());  // this thread keeps IEEE subnormals
#ifdef PRISM_HAS_MXCSR
    {
        const prism::FlushDenormals flush;
        CHECK(flushes());
    }
#endif
    CHECK_FALSE(flushes());
    scene::Scene world = furnace();
    world.cameras[0].num_samples = 4;
    world.cameras[0].width = world.cameras[0].height = 40;  // several tiles
    prism::RendererSettings settings;
    settings.backface_culling = prism::BackfaceCulling::none;  // the camera is inside the cube
    const prism::Renderer<PathConfig<Real>> renderer(world, settings);
    std::atomic<int> tiles = 0, pixels = 0, flushed = 0;
    const prism::Image image = renderer.render(world.cameras[0], 0, 0, [&](int tile_pixels) {
        ++tiles;
        pixels += tile_pixels;
        if (flushes()) ++flushed;
    });
    CHECK(tiles > 1);
    CHECK(pixels == 40 * 40);
    CHECK(flushed == 0);
    CHECK_FALSE(flushes());
    CHECK(mean_of(image) > 1);  // the furnace rendered (1.875 when converged)
}

TEST_CASE("dispatch: the path tracer only for scenes with a path-traced camera") {
    using Whitted = prism::Config<float, prism::Bvh<prism::Watertight>, prism::AllLightSet, prism::all_features,
                                  prism::Whitted>;
    scene::Needs needs;
    needs.lights = scene::bit(scene::LightKind::object);
    CHECK(Whitted::covers(needs));
    CHECK(PathConfig<float>::covers(needs));
    needs.path_tracing = true;
    CHECK_FALSE(Whitted::covers(needs));
    CHECK(PathConfig<float>::covers(needs));
    // The shipped list tries the ray tracers first: a scene without a path-traced camera never
    // reaches the path tracer.
    scene::Scene world = furnace();
    std::ostringstream log;
    prism::RenderOptions options;
    options.max_samples = 1;
    prism::render_scene(world, options, log);
    CHECK(log.str().find("path tracing") == std::string::npos);
}
