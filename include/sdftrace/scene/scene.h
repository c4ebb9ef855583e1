// A scene: the field tree, materials, lights, camera and render settings. Parsing gives a
// description whose grid files, meshes and baked subtrees are asset requests (pending grid nodes);
// prepareScene (prepare_scene.h) loads and bakes them; planRender (plan_render.h) compiles the
// prepared scene for the integrators.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/bake/texture_coords.h"
#include "sdftrace/field/device_resident_grid.h"
#include "sdftrace/field/node.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/math/camera.h"
#include "sdftrace/render/lighting.h"
#include "sdftrace/render/render_settings.h"
#include "sdftrace/render/texture.h"

namespace sdft {

class MeshAccel;  // scene/mesh_accel.h

// A grid the scene needs: a grid file, a mesh baked to a grid, or a subtree sampled into one.
struct AssetRequest {
    enum class Kind { GridFile, Mesh, Subtree };
    Kind kind = Kind::GridFile;
    std::string where;       // "<scene file>: <JSON path>", the start of its error messages
    std::string path;        // GridFile, Mesh: the file (relative paths resolved)
    MeshBakeOptions bake;    // Mesh
    NodePtr subtree;         // Subtree: the field to sample (may hold assets)
    SampleOptions sampling;  // Subtree
    std::optional<TexcoordOptions> texcoords;  // Subtree: projected (u, v) (Liktor §5.5.2)
    std::string key;  // identical requests (same file and options) share one grid; empty: none
    // Mesh: regenerated every frame (issue 16): rebaked, or by RTSDF's pipeline with temporal
    // accumulation (eq. 1, decay `alpha`) whose history the AssetCache keeps under `where`.
    enum class Dynamic { None, Rebake, Rtsdf };
    Dynamic dynamic = Dynamic::None;
    float alpha = 0.95f;
    // Mesh: a skinned or morph-animated file posed by its own animation (io/mesh_animation.h)
    // at `seconds` into the clip named `clip` (or numbered `clipIndex` when `clip` is empty),
    // wrapped into the clip when `loop`, else clamped to it.
    struct Play {
        std::string where;  // "<scene file>: <JSON path of the play block>"
        std::string clip;
        int clipIndex = 0;
        double seconds = 0;
        bool loop = true;
    };
    std::optional<Play> play;
};

// A check that needs the bounds of pending grids, run once they are loaded: copies of a
// repetition's child must not overlap.
struct RepeatCheck {
    NodePtr child;
    Vec3 cell, count;
    std::string where;  // "<scene file>: <JSON path of the repeat>"
};

// The time span of an animated scene (its "animation" block, docs/scene-format.md "Animation"):
// without the block, the span of its keyframes at 30 frames per second.
struct SceneTime {
    double start = 0, end = 0;  // seconds
    double fps = 30;
    bool animated = false;  // the scene has keyframed values
};

struct Scene {
    NodePtr root;
    std::vector<AssetRequest> assets;  // requests of pending grid nodes (node::gridAsset)
    std::vector<RepeatCheck> repeatChecks;
    bool prepared() const { return !root || !hasPendingAssets(*root); }
    std::vector<Material> materials;
    std::vector<Texture> textures;     // referenced by materials
    std::vector<TextureImage> images;  // decoded image files, referenced by textures
    Lighting lighting;
    CameraDesc camera;
    RenderSettings settings;
    SceneTime time;
    // The triangles each mesh grid was baked from (prepareScene), for primary rays on the
    // triangles (RenderSettings::primaryTriangles).
    std::map<const Grid*, std::shared_ptr<const TriangleMesh>> meshes;
    // Their BVHs and normals where primary rays hit triangles, from the cache (prepareScene):
    // shared by the frames of an animation; planRender builds what is missing.
    std::map<const TriangleMesh*, std::shared_ptr<const MeshAccel>> meshAccels;
    // Grids whose current values are on the GPU (prepareScene, for `render --device cuda`).
    std::vector<DeviceResidentGrid> deviceGrids;
};

}  // namespace sdft
