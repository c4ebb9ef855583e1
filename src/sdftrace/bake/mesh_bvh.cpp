#include "sdftrace/bake/mesh_bvh.h"

#include <embree3/rtcore.h>

#include <cmath>
#include <cstring>

#include "sdftrace/bake/closest_point.h"
#include "sdftrace/bake/embree_device.h"
#include "sdftrace/core/error.h"

namespace sdft {

// A triangle's vertices and bounds side by side: the closest-point callback reads one cache line
// pair, and rejects by the box before the exact test.
struct PackedTriangle {
    Vec3 a, b, c;
    Vec3 lo, hi;
};

struct MeshBvh::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<PackedTriangle> triangles;
};

namespace {

RTCRayHit rayHit(Vec3 origin, Vec3 direction, float tnear, float tfar = INFINITY) {
    RTCRayHit rh;
    rh.ray.org_x = origin.x;
    rh.ray.org_y = origin.y;
    rh.ray.org_z = origin.z;
    rh.ray.dir_x = direction.x;
    rh.ray.dir_y = direction.y;
    rh.ray.dir_z = direction.z;
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.mask = 0xFFFFFFFF;
    rh.ray.flags = 0;
    rh.ray.time = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    return rh;
}

struct ClosestQuery {
    const PackedTriangle* triangles;
    MeshBvh::Closest best;
};

bool closestCallback(RTCPointQueryFunctionArguments* args) {
    auto* q = static_cast<ClosestQuery*>(args->userPtr);
    const PackedTriangle& t = q->triangles[args->primID];
    Vec3 p(args->query->x, args->query->y, args->query->z);
    Vec3 out = max(max(t.lo - p, p - t.hi), Vec3(0.0f));
    float r = args->query->radius;
    if (dot(out, out) > r * r) return false;
    Vec3 c = closestPointOnTriangle(p, t.a, t.b, t.c);
    float d = length(p - c);
    if (std::isnan(d)) {  // zero area: Ericson's face region divides by it; the edges remain
        const Vec3 corners[3] = {t.a, t.b, t.c};
        for (int e = 0; e < 3; ++e) {
            const Vec3 a = corners[e], ab = corners[(e + 1) % 3] - a;
            const float len2 = dot(ab, ab);
            const float s = len2 > 0 ? clampf(dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
            const Vec3 on = a + ab * s;
            if (const float de = length(p - on); !(de >= d)) {
                d = de;
                c = on;
            }
        }
    }
    if (d <= args->query->radius) {
        args->query->radius = d;  // shrink the search
        q->best = {d, c, args->primID};
        return true;
    }
    return false;
}
}  // namespace

// One Embree device for the process: starting one costs milliseconds (it sets up its task
// scheduler), more than building a BVH of a small mesh; devices are thread-safe.
RTCDevice embreeDevice() {
    static RTCDevice device = rtcNewDevice(nullptr);
    if (!device) throw InputError("cannot start Embree (rtcNewDevice failed)");
    return device;
}

MeshBvh::MeshBvh(const TriangleMesh& mesh) : m_impl(std::make_unique<Impl>()), m_mesh(mesh) {
    m_impl->device = embreeDevice();
    m_impl->scene = rtcNewScene(m_impl->device);
    // windingChange() hands its intersect context a filter that sees every crossing.
    rtcSetSceneFlags(m_impl->scene, RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
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
    for (const auto& t : mesh.triangles) {
        Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
        m_impl->triangles.push_back({a, b, c, min(a, min(b, c)), max(a, max(b, c))});
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(m_impl->scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(m_impl->scene);
}

MeshBvh::~MeshBvh() {
    if (m_impl->scene) rtcReleaseScene(m_impl->scene);
}

MeshBvh::Closest MeshBvh::closest(Vec3 p, float radius) const {
    RTCPointQuery q = pointQueryAt(p, radius);
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    ClosestQuery data{m_impl->triangles.data(), {}};
    rtcPointQuery(m_impl->scene, &q, &ctx, closestCallback, &data);
    return data.best;
}

MeshBvh::Hit MeshBvh::firstHit(const Ray& ray, float tnear, float tfar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    // Embree wants tnear >= 0: start from the origin moved back by -tnear instead.
    float back = std::fmin(tnear, 0.0f);
    RTCRayHit rh = rayHit(ray.origin + ray.direction * back, ray.direction, std::fmax(tnear, 0.0f),
                          tfar - back);
    rtcIntersect1(m_impl->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {};
    // Embree's geometry normal is (b - a) x (c - a): the side needs no second look at the
    // triangle (a cache miss per ray on large meshes).
    const Vec3 n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    return {rh.ray.tfar + back, dot(ray.direction, n) < 0, rh.hit.primID, rh.hit.u, rh.hit.v, n};
}

namespace {
// Every crossing of a segment, gathered by the context filter that rejects each hit so that the
// traversal goes on (a face met twice, through spatial splits, is counted once).
struct CrossingContext {
    RTCIntersectContext base;  // first: Embree hands the filter this pointer
    const PackedTriangle* triangles;
    Vec3 dir;
    float margin;
    int change = 0;
    bool sure = true;
    uint32_t seen[16];
    int count = 0;
};

void crossingFilter(const RTCFilterFunctionNArguments* args) {
    auto* c = reinterpret_cast<CrossingContext*>(args->context);
    args->valid[0] = 0;
    const uint32_t prim = RTCHitN_primID(args->hit, args->N, 0);
    for (int k = 0; k < c->count; ++k)
        if (c->seen[k] == prim) return;
    if (c->count == 16) {
        c->sure = false;
        return;
    }
    c->seen[c->count++] = prim;
    const float t = RTCRayN_tfar(args->ray, args->N, 0);
    const float u = RTCHitN_u(args->hit, args->N, 0), v = RTCHitN_v(args->hit, args->N, 0);
    const PackedTriangle& tri = c->triangles[prim];
    const Vec3 n = cross(tri.b - tri.a, tri.c - tri.a);
    const float facing = dot(c->dir, n), m = c->margin;
    if (t < m || t > 1 - m || u < m || v < m || 1 - u - v < m ||
        !(std::fabs(facing) > 1e-3f * length(c->dir) * length(n)))
        c->sure = false;
    c->change += facing < 0 ? 1 : -1;
}
}  // namespace

bool MeshBvh::windingChange(Vec3 a, Vec3 b, int& change, float margin) const {
    CrossingContext c;
    rtcInitIntersectContext(&c.base);
    c.base.filter = crossingFilter;
    c.triangles = m_impl->triangles.data();
    c.dir = b - a;
    c.margin = margin;
    RTCRayHit rh = rayHit(a, c.dir, 0, 1.0f);
    rtcIntersect1(m_impl->scene, &c.base, &rh);
    change = c.change;
    return c.sure;
}

int MeshBvh::crossings(const Ray& ray) const {
    int count = 0;
    float tnear = 0;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (int guard = 0; guard < 100000; ++guard) {
        RTCRayHit rh = rayHit(ray.origin, ray.direction, tnear);
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
