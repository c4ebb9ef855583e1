// Lone-grid scenes traced by Jamriška's two-level DDA (`sdftrace render field.sdfg` or a mesh
// file), for the per-pixel path's tests (render/primary_pixel_test.cpp, direct_pixel_test.cpp on
// the CPU, gpu/gpu_render_test.cpp on a GPU): an analytic scene sampled into a sparse grid of
// 4-blocks and into a dense grid, and Suzanne (data/meshes) baked exactly into a sparse grid of
// 8-blocks. Each is framed as the CLI frames a grid file, with its key and fill lights.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/field/node.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/scene/grid_scene.h"

namespace sdft::testing {

inline std::vector<std::pair<std::string, Scene>> ddaTestScenes(int width, int height) {
    std::vector<std::pair<std::string, Scene>> out;
    auto add = [&](const std::string& name, Grid grid) {
        auto g = std::make_shared<const Grid>(std::move(grid));
        Scene scene = sceneForObject(node::grid(g), g->surfaceBounds());
        scene.camera.width = width;
        scene.camera.height = height;
        scene.settings.minMaxResolution = 0;  // per pixel, rays start at the grid's box
        out.emplace_back(name, std::move(scene));
    };
    const NodePtr analytic = node::unite(
        {node::torus(0.8f, 0.25f), node::translate(node::box({0.5f, 0.6f, 0.5f}), {0, 0.2f, 0}),
         node::translate(node::sphere(0.35f), {-1.1f, 0.6f, 0.3f})});
    const Tape tape = compileTape(analytic, {.boundsCulling = false});
    SampleOptions o;
    o.resolution = 64;
    o.blockSize = 4;
    add("analytic sparse", sampleGrid(tape, nodeBounds(*analytic), o));
    o.kind = GridKind::Dense;
    add("analytic dense", sampleGrid(tape, nodeBounds(*analytic), o));
    MeshBakeOptions m;
    m.sampling.resolution = 48;
    m.sampling.blockSize = 8;
    add("suzanne sparse",
        bakeMesh(loadMesh(std::string(SDFT_SOURCE_DIR) + "/data/meshes/suzanne.obj"), m).grid);
    return out;
}

}  // namespace sdft::testing
