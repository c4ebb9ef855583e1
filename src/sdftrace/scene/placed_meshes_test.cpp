// RTSDF's hybrid mode (primary_triangles): primary rays on the meshes' triangles, shadows in
// their SDFs (issue 16).
#include "placed_meshes.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/render/direct_pixel.h"
#include "sdftrace/render/renderer.h"
#include "sdftrace/scene/animated_scene.h"
#include "sdftrace/scene/mesh_accel.h"
#include "sdftrace/scene/plan_render.h"

namespace sdft {
namespace {

const std::string kMeshes = std::string(SDFT_SOURCE_DIR) + "/data/meshes/";

// The bunny placed by a scale, a rotation and a translation on an analytic floor.
std::string bunnyScene(bool triangles, const std::string& extra = "") {
    return R"({"camera": {"eye": [0.2, 0.9, 2.2], "target": [0, 0.35, 0], "fov": 40, "width": 160, "height": 120},
      "lights": [{"type": "directional", "direction": [-0.4, -1, -0.5], "intensity": 2}],
      "objects": [
        {"type": "box", "size": [4, 0.1, 4], "translate": [0, -0.05, 0]},
        {"mesh": "bunny_npm.obj", "resolution": 96, "scale": 0.08,
         "rotate": {"axis": [0, 1, 0], "angle": 30}, "translate": [0.05, 0, 0]}],
      "render": {"primary_triangles": )" +
           std::string(triangles ? "true" : "false") + extra + "}}";
}

Film renderText(const std::string& text, Scene* prepared = nullptr) {
    AssetCache cache;
    Scene scene = AnimatedScene::fromText(text, "bunny.json", kMeshes).at(0, cache);
    const RenderPlan plan = planRender(scene);
    Film film(plan.camera.width, plan.camera.height);
    render(plan, film);
    if (prepared) *prepared = scene;
    return film;
}

// Each pixel's depth is the first hit of its ray against the floor or the placed triangles, cast
// here independently (the mesh moved into the world, one BVH); the SDF render agrees with it off
// silhouettes to within about a voxel.
TEST(PrimaryTriangles, PrimaryRaysHitTheTriangles) {
    Scene scene;
    const Film hybrid = renderText(bunnyScene(true), &scene);
    const Film sdf = renderText(bunnyScene(false));
    TriangleMesh world = loadMesh(kMeshes + "bunny_npm.obj");
    const Mat3 r = rotationAxisAngle(Vec3(0, 1, 0), 30);
    for (Vec3& p : world.positions) p = r * (p * 0.08f) + Vec3(0.05f, 0, 0);
    const MeshBvh bvh(world);
    const Camera camera(scene.camera);
    const float voxel = 0.08f * 9.91f / 96;  // the bunny is 9.91 units across before scaling
    const int w = scene.camera.width, h = scene.camera.height;
    std::vector<float> mesh(static_cast<size_t>(w) * h, INFINITY);
    std::vector<bool> onMesh(mesh.size(), false);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            const Ray ray = camera.pixelRay(x, y);
            mesh[i] = bvh.firstHit(ray).t;
            const float floorT = ray.direction.y < 0 ? -ray.origin.y / ray.direction.y : INFINITY;
            onMesh[i] = mesh[i] < floorT;
            EXPECT_TRUE(std::isfinite(hybrid.color[3 * i]));
        }
    int triangleHits = 0, agree = 0, compared = 0;
    for (int y = 1; y + 1 < h; ++y)
        for (int x = 1; x + 1 < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            if (!onMesh[i]) continue;
            ++triangleHits;
            EXPECT_NEAR(hybrid.depth[i], mesh[i], 1e-4f * mesh[i]) << x << ", " << y;
            bool interior = true;  // off silhouettes: the 3 x 3 neighbourhood is on the mesh,
            for (int dy = -1; dy <= 1; ++dy)  // at depths within 2 voxels of this one
                for (int dx = -1; dx <= 1; ++dx) {
                    const size_t j = static_cast<size_t>(y + dy) * w + (x + dx);
                    interior = interior && onMesh[j] && std::fabs(mesh[j] - mesh[i]) < 2 * voxel;
                }
            if (!interior) continue;
            ++compared;
            agree += std::fabs(sdf.depth[i] - mesh[i]) < voxel;
        }
    EXPECT_GT(triangleHits, 2000);
    EXPECT_GT(compared, 500);
    EXPECT_GT(agree, 0.97 * compared) << agree << " of " << compared;
}

// A coarse sphere mesh (10 x 20 facets) in a coarse grid (16 cells), lit obliquely: where its
// triangles face the light, nothing shadows them. The shading point sits a voxel off the
// triangle (RTSDF §2.5.3), outside the SDF's error; a point a voxel below it is shadowed at 1576
// of 1577 such pixels.
TEST(PrimaryTriangles, TrianglesDoNotShadowThemselvesInTheSdf) {
    const std::string obj = (std::filesystem::temp_directory_path() /
                             ("sdft_sphere_" + std::to_string(getpid()) + ".obj"))
                                .string();
    {
        std::ofstream out(obj);
        const int rings = 10, segments = 20;
        for (int r = 0; r <= rings; ++r)
            for (int s = 0; s < segments; ++s) {
                const double th = M_PI * r / rings, ph = 2 * M_PI * s / segments;
                out << "v " << std::sin(th) * std::cos(ph) << " " << std::cos(th) << " "
                    << std::sin(th) * std::sin(ph) << "\n";
            }
        for (int r = 0; r < rings; ++r)
            for (int s = 0; s < segments; ++s) {
                const int a = r * segments + s + 1, b = r * segments + (s + 1) % segments + 1;
                const int c = a + segments, d = b + segments;
                out << "f " << a << " " << b << " " << c << "\nf " << b << " " << d << " " << c
                    << "\n";
            }
    }
    for (const char* method : {"hard", "soft"}) {
        const std::string text =
            std::string(
                R"({"camera": {"eye": [0, 1.5, 3], "target": [0, 0, 0], "width": 96, "height": 72},
              "lights": [{"type": "directional", "direction": [-1, -1, -0.5]}],
              "objects": [{"mesh": ")") +
            obj + R"(", "resolution": 16, "band": 3}],
              "render": {"primary_triangles": true, "shadow_method": ")" +
            method + R"("}})";
        AssetCache cache;
        const Scene scene = AnimatedScene::fromText(text, "sphere.json").at(0, cache);
        const RenderPlan plan = planRender(scene);
        Film film(plan.camera.width, plan.camera.height);
        render(plan, film);
        const Vec3 toLight = normalize(Vec3(1, 1, 0.5f));
        int lit = 0, dark = 0;
        for (size_t i = 0; i < film.pixels(); ++i) {
            const Vec3 n(film.normal[3 * i], film.normal[3 * i + 1], film.normal[3 * i + 2]);
            if (!std::isfinite(film.depth[i]) || dot(n, toLight) < 0.3f) continue;
            ++lit;
            dark += film.shadow[i] < 0.9f;
        }
        EXPECT_GT(lit, 800) << method;
        EXPECT_LT(dark, lit / 200) << method << ": " << dark << " of " << lit << " self-shadowed";
    }
    std::filesystem::remove(obj);
}

// The per-pixel path's tables (an LBVH per mesh, the placement as affine maps) hit where the
// renderer's Embree BVHs hit: from the example's camera, close to the bunny, and at grazing angles
// along the floor. Two ray-triangle tests differ only on triangle edges (a ray between two
// triangles may slip through one test and not the other), so at most 0.2 % of the rays may
// disagree on hit or miss; where both hit, t within 1e-4 t, the same bias, normals within 0.5°
// except where they took different triangles (edges, at most 0.5 %).
TEST(PrimaryTriangles, LbvhTablesHitWhereEmbreeHits) {
    AssetCache cache;
    const Scene scene =
        AnimatedScene::fromText(bunnyScene(true), "bunny.json", kMeshes).at(0, cache);
    const RenderPlan plan = planRender(scene);
    ASSERT_TRUE(plan.meshPrimary);
    MeshPrimaryTables tables = plan.meshPrimary->tables();
    ASSERT_EQ(tables.meshes.size(), 1u);
    const MeshPrimaryView view = tables.view();
    struct Eye {
        Vec3 eye, target;
    };
    int rays = 0, hits = 0, hitMismatch = 0, normalOff = 0;
    for (const Eye& e : {Eye{{0.2f, 0.9f, 2.2f}, {0, 0.35f, 0}},       // the example's
                         Eye{{0.3f, 0.45f, 0.55f}, {0.05f, 0.3f, 0}},  // close
                         Eye{{1.6f, 0.03f, 0.4f}, {0, 0.05f, 0}}}) {   // grazing the floor
        CameraDesc d = plan.camera;
        d.eye = e.eye;
        d.target = e.target;
        d.width = 120;
        d.height = 90;
        const Camera camera(d);
        for (int y = 0; y < d.height; ++y)
            for (int x = 0; x < d.width; ++x) {
                const Ray r = camera.pixelRay(x, y);
                const MeshPrimary::Hit a = plan.meshPrimary->firstHit(r, INFINITY);
                const MeshPrimaryHit b = meshPrimaryHit(view, r, INFINITY);
                ++rays;
                if (std::isfinite(a.t) != std::isfinite(b.t)) {
                    ++hitMismatch;
                    continue;
                }
                if (!std::isfinite(a.t)) continue;
                ++hits;
                EXPECT_NEAR(a.t, b.t, 1e-4f * a.t) << x << "," << y;
                EXPECT_EQ(a.bias, b.bias);
                EXPECT_NEAR(length(b.normal), 1.0f, 1e-5f);
                normalOff += dot(a.normal, b.normal) < std::cos(0.5f * kPi / 180);
            }
    }
    EXPECT_GT(hits, rays / 8);
    EXPECT_LE(hitMismatch, rays / 500);
    EXPECT_LE(normalOff, hits / 200);
}

// A mesh whose grid lives on the GPU (render --device cuda's RTSDF frames, DeviceResidentGrid)
// is posed there too: the plan builds no host BVH or normals for it and its tables carry the
// device state instead of arrays, for the GPU renderer to bind the baker's (GpuMeshBaker::surface;
// GpuCompleteGrid.ResidentFramesRenderAsFramesBakedToTheHost renders it on a GPU); the host view
// leaves it out and the CPU renderer refuses the plan. Other meshes keep their host arrays.
TEST(PrimaryTriangles, AMeshPosedOnTheGpuGetsNoHostBvh) {
    AssetCache cache;
    Scene scene = AnimatedScene::fromText(bunnyScene(true), "bunny.json", kMeshes).at(0, cache);
    ASSERT_EQ(scene.meshes.size(), 1u);
    const Grid* bunny = scene.meshes.begin()->first;
    const RenderPlan host = planRender(scene);
    ASSERT_TRUE(host.meshPrimary);
    const MeshPrimaryTables hostTables = host.meshPrimary->tables();
    ASSERT_EQ(hostTables.meshes.size(), 1u);
    EXPECT_FALSE(hostTables.meshes[0].device);
    EXPECT_FALSE(hostTables.meshes[0].nodes.empty());
    EXPECT_EQ(directPixelTables(host).meshView.count, 1);
    // A stand-in state: the plan only carries it, the GPU renderer alone reads it.
    int marker = 0;
    const std::shared_ptr<RtsdfDeviceState> state(std::make_shared<int>(0),
                                                  reinterpret_cast<RtsdfDeviceState*>(&marker));
    scene.deviceGrids.push_back({bunny, state});
    const RenderPlan device = planRender(scene);
    ASSERT_TRUE(device.meshPrimary);
    const MeshPrimaryTables tables = device.meshPrimary->tables();
    ASSERT_EQ(tables.meshes.size(), 1u);
    EXPECT_EQ(tables.meshes[0].device, state);
    EXPECT_TRUE(tables.meshes[0].nodes.empty());
    EXPECT_TRUE(tables.meshes[0].normals.empty());
    EXPECT_TRUE(tables.meshes[0].indices.empty());
    // The placement still goes along: the GPU renderer carries rays into the mesh by it.
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            EXPECT_EQ(tables.meshes[0].toLocal.linear.m[r][c],
                      hostTables.meshes[0].toLocal.linear.m[r][c]);
    EXPECT_EQ(tables.meshes[0].bias, hostTables.meshes[0].bias);
    EXPECT_EQ(directPixelTables(device).meshView.count, 0);
    Film film(device.camera.width, device.camera.height);
    EXPECT_THROW(render(device, film), InputError);
}

// A rigid mesh moved by keyframes keeps its triangles from frame to frame, and the frames' plans
// share its BVH and normals from the cache (AssetCache::meshAccel) instead of building them per
// plan (the 69k-triangle Stanford bunny: 60 ms of a 190 ms frame here): the same image as a plan
// that builds its own; the cache lets them go with the mesh; no BVH without triangle primaries.
TEST(PrimaryTriangles, FramesShareARigidMeshsBvh) {
    auto text = [](bool triangles) {
        return R"({"camera": {"eye": [0.2, 0.9, 2.2], "target": [0, 0.35, 0], "fov": 40,
                              "width": 96, "height": 72},
          "lights": [{"type": "directional", "direction": [-0.4, -1, -0.5], "intensity": 2}],
          "objects": [{"type": "box", "size": [4, 0.1, 4], "translate": [0, -0.05, 0]},
            {"mesh": "bunny_npm.obj", "resolution": 48, "scale": 0.08,
             "rotate": {"axis": [0, 1, 0], "angle": {"keyframes": [{"time": 0, "value": 0},
                                                                     {"time": 1, "value": 90}]}}}],
          "render": {"shadow_method": "soft", "primary_triangles": )" +
               std::string(triangles ? "true" : "false") + "}}";
    };
    const AnimatedScene anim = AnimatedScene::fromText(text(true), "rigid.json", kMeshes);
    AssetCache cache;
    std::shared_ptr<const MeshAccel> first;
    for (double t : {0.0, 0.5, 1.0}) {
        AnimatedScene::InstantAssets used;
        Scene scene = anim.at(t, cache, {}, &used);
        cache.keepOnly(used.keys);
        ASSERT_EQ(scene.meshAccels.size(), 1u) << t;
        const std::shared_ptr<const MeshAccel> accel = scene.meshAccels.begin()->second;
        if (!first) first = accel;
        EXPECT_EQ(accel, first) << t;
        EXPECT_EQ(cache.meshAccelCount(), 1u) << t;
        const RenderPlan shared = planRender(scene);
        scene.meshAccels.clear();  // the plan builds its own
        const RenderPlan own = planRender(scene);
        Film a(96, 72), b(96, 72);
        render(shared, a);
        render(own, b);
        EXPECT_EQ(a.color, b.color) << t;
        EXPECT_EQ(a.depth, b.depth) << t;
    }
    cache.keepOnly({});  // the mesh leaves the cache, and its BVH with it
    EXPECT_EQ(cache.meshAccelCount(), 0u);
    AssetCache plain;
    EXPECT_TRUE(AnimatedScene::fromText(text(false), "rigid.json", kMeshes)
                    .at(0, plain)
                    .meshAccels.empty());
    EXPECT_EQ(plain.meshAccelCount(), 0u);
}

}  // namespace
}  // namespace sdft
