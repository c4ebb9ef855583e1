#include "sdftrace/scene/load_input.h"

#include <memory>

#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/mesh_file.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/scene/grid_scene.h"
#include "sdftrace/scene/parse_scene.h"
#include "sdftrace/scene/prepare_scene.h"

namespace sdft {

LoadedInput loadSceneInput(const std::string& input, bool progress, const MeshBaker& meshBaker,
                           bool gapLattice) {
    if (input.empty()) return {demoScene(), ""};
    if (isMeshFile(input)) {
        MeshReport report;
        TriangleMesh mesh = loadMesh(input, &report);
        MeshBakeOptions options;
        options.progress = progress;
        auto grid = sceneGrid(bakeMesh(mesh, options).grid, gapLattice);
        return {sceneForObject(node::grid(grid), grid->surfaceBounds()),
                input + ": " + report.summary() + "; baked exactly at " +
                    std::to_string(options.sampling.resolution) + " cells"};
    }
    if (isGridFile(input)) {
        auto grid = sceneGrid(loadGridFile(input), gapLattice);
        const Bounds3 frame = grid->surfaceBounds();
        if (frame.empty())
            throw InputError(input + ": the grid contains no surface (no sign change)");
        return {sceneForObject(node::grid(grid), frame), ""};
    }
    LoadedInput out{describeSceneFile(input), ""};
    prepareScene(out.scene, PrepareOptions{.progress = progress, .bakeMesh = meshBaker});
    return out;
}

bool loneGridReadsDistances(const RenderSettings& s) {
    if (s.gridTracer != GridTracerKind::Dda || s.pathTracing || s.ambientOcclusion) return true;
    return s.shadows && s.shadowMethod != ShadowMethod::Hard &&
           s.shadowMethod != ShadowMethod::Distributed;
}

}  // namespace sdft
