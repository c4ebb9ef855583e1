// The meshes of a scene as triangles for primary rays (render/mesh_primary.h, RTSDF's hybrid
// mode): each mesh keeps its Embree BVH in its own coordinates and rays are carried into them by
// the mesh's placement (render/motion.h), so a moving rigid mesh is not rebuilt. Internal to the
// scene module.
#pragma once

#include <memory>
#include <vector>

#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/render/mesh_primary.h"
#include "sdftrace/render/motion.h"
#include "sdftrace/scene/mesh_accel.h"

namespace sdft {

struct PlacedMesh {
    std::shared_ptr<const TriangleMesh> mesh;
    // Its BVH and normals (in the mesh's coordinates), shared with the other frames' plans; none
    // when `device`.
    std::shared_ptr<const MeshAccel> accel;
    Placement placement;  // mesh to world
    float bias = 0;       // MeshPrimary::Hit::bias
    // A mesh whose grid lives on the GPU (DeviceResidentGrid): its posed triangles are there too
    // (GpuMeshBaker::surface), so neither the BVH nor the normals are built on the host. Only a
    // GPU renderer reads it.
    std::shared_ptr<RtsdfDeviceState> device;
};

class PlacedMeshes : public MeshPrimary {
  public:
    explicit PlacedMeshes(std::vector<PlacedMesh> meshes) : m_meshes(std::move(meshes)) {}
    Hit firstHit(const Ray& ray, float tMax) const override;
    MeshPrimaryTables tables() const override;

  private:
    std::vector<PlacedMesh> m_meshes;
};

}  // namespace sdft
