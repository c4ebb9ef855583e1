// What primary rays on a mesh's triangles need beyond the triangles (RTSDF's hybrid mode,
// render/mesh_primary.h): the mesh's Embree BVH and smooth vertex normals for the CPU renderer,
// and the LBVH arrays a GPU renderer uploads (built on first use). Built once per mesh and shared
// by the plans of an animation's frames (AssetCache::meshAccel): a rigid mesh moved by keyframes
// is not rebuilt every frame.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "sdftrace/bake/lbvh.h"
#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/bake/triangle_mesh.h"

namespace sdft {

// Area-weighted unit vertex normals of a mesh, for shading its triangles smoothly ((0, 1, 0)
// where a vertex's triangles have no area).
std::vector<Vec3> smoothNormals(const TriangleMesh& mesh);

class MeshAccel {
  public:
    explicit MeshAccel(std::shared_ptr<const TriangleMesh> mesh);

    const std::shared_ptr<const TriangleMesh>& meshPointer() const { return m_mesh; }
    const MeshBvh& bvh() const { return m_bvh; }
    const std::vector<Vec3>& normals() const { return m_normals; }

    // The mesh's LBVH (bake/lbvh.h) and its triangles' vertex indices, 3 each, as the per-pixel
    // path reads them (MeshPrimaryTables); built on the first call, from any thread.
    struct LbvhArrays {
        std::vector<LbvhNode> nodes;
        std::vector<LbvhTriangle> triangles;
        std::vector<uint32_t> indices;
    };
    const LbvhArrays& lbvh() const;

  private:
    std::shared_ptr<const TriangleMesh> m_mesh;
    MeshBvh m_bvh;
    std::vector<Vec3> m_normals;
    mutable std::once_flag m_lbvhOnce;
    mutable LbvhArrays m_lbvh;
};

}  // namespace sdft
