#include "sdftrace/bake/mesh_bvh.h"

#include <embree3/rtcore.h>

#include <cmath>
#include <cstring>

#include "sdftrace/bake/closest_point.h"
#include "sdftrace/core/error.h"

namespace sdft {

struct MeshBvh::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
};

namespace {
struct ClosestQuery {
    const TriangleMesh* mesh;
    float best;
};

bool closestCallback(RTCPointQueryFunctionArguments* args) {
    auto* q = static_cast<ClosestQuery*>(args->userPtr);
    const auto& t = q->mesh->triangles[args->primID];
    Vec3 p(args->query->x, args->query->y, args->query->z);
    Vec3 c = closestPointOnTriangle(p, q->mesh->positions[t[0]], q->mesh->positions[t[1]],
                                    q->mesh->positions[t[2]]);
    float d = length(p - c);
    if (d < args->query->radius) {
        args->query->radius = d;  // shrink the search
        q->best = d;
        return true;
    }
    return false;
}
}  // namespace

MeshBvh::MeshBvh(const TriangleMesh& mesh) : m_impl(std::make_unique<Impl>()), m_mesh(mesh) {
    m_impl->device = rtcNewDevice(nullptr);
    if (!m_impl->device) throw InputError("cannot start Embree (rtcNewDevice failed)");
    m_impl->scene = rtcNewScene(m_impl->device);
    rtcSetSceneBuildQuality(m_impl->scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = rtcNewGeometry(m_impl->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                           RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                           mesh.positions.size()));
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        vb[3 * i + 0] = mesh.positions[i].x;
        vb[3 * i + 1] = mesh.positions[i].y;
        vb[3 * i + 2] = mesh.positions[i].z;
    }
    auto* ib = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(unsigned), mesh.triangles.size()));
    std::memcpy(ib, mesh.triangles.data(), mesh.triangles.size() * 3 * sizeof(unsigned));
    rtcCommitGeometry(geom);
    rtcAttachGeometry(m_impl->scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(m_impl->scene);
}

MeshBvh::~MeshBvh() {
    if (m_impl->scene) rtcReleaseScene(m_impl->scene);
    if (m_impl->device) rtcReleaseDevice(m_impl->device);
}

float MeshBvh::closestDistance(Vec3 p) const {
    RTCPointQuery q;
    q.x = p.x;
    q.y = p.y;
    q.z = p.z;
    q.time = 0;
    q.radius = INFINITY;
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    ClosestQuery data{&m_mesh, INFINITY};
    rtcPointQuery(m_impl->scene, &q, &ctx, closestCallback, &data);
    return data.best;
}

int MeshBvh::crossings(const Ray& ray) const {
    int count = 0;
    float tnear = 0;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (int guard = 0; guard < 100000; ++guard) {
        RTCRayHit rh;
        rh.ray.org_x = ray.origin.x;
        rh.ray.org_y = ray.origin.y;
        rh.ray.org_z = ray.origin.z;
        rh.ray.dir_x = ray.direction.x;
        rh.ray.dir_y = ray.direction.y;
        rh.ray.dir_z = ray.direction.z;
        rh.ray.tnear = tnear;
        rh.ray.tfar = INFINITY;
        rh.ray.mask = 0xFFFFFFFF;
        rh.ray.flags = 0;
        rh.ray.time = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(m_impl->scene, &ctx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
        ++count;
        // Continue just past this hit (relative step: robust at any scale).
        tnear = rh.ray.tfar + std::fmax(1e-6f, rh.ray.tfar * 1e-6f);
    }
    return count;
}

bool MeshBvh::insideByParity(Vec3 p) const {
    static const Vec3 dirs[3] = {normalize(Vec3(0.5773f, 0.5813f, 0.5732f)),
                                 normalize(Vec3(-0.7071f, 0.0123f, 0.7071f)),
                                 normalize(Vec3(0.0412f, -0.9991f, 0.0217f))};
    int votes = 0;
    for (const Vec3& d : dirs) votes += crossings({p, d}) % 2;
    return votes >= 2;
}

}  // namespace sdft
