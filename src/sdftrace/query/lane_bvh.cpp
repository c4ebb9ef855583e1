#include "sdftrace/query/lane_bvh.h"

#include <cmath>

#include "sdftrace/bake/embree_device.h"

namespace sdft {

namespace {

// A group's box, as the BVH's build asks for it.
void groupBounds(const RTCBoundsFunctionArguments* args) {
    const Bounds3& box = static_cast<const Bounds3*>(args->geometryUserPtr)[args->primID];
    RTCBounds* b = args->bounds_o;
    b->lower_x = box.lo.x;
    b->lower_y = box.lo.y;
    b->lower_z = box.lo.z;
    b->upper_x = box.hi.x;
    b->upper_y = box.hi.y;
    b->upper_z = box.hi.z;
}

struct Query {
    const LaneGroup* groups;
    uint32_t best = UINT32_MAX;
    float d2 = INFINITY;
};

// A group the traversal reached: its eight triangles measured at once; the sphere shrinks to the
// nearest.
bool groupClosest(RTCPointQueryFunctionArguments* args) {
    auto* q = static_cast<Query*>(args->userPtr);
    const Vec3 p(args->query->x, args->query->y, args->query->z);
    const float r = args->query->radius;
    uint32_t id = UINT32_MAX;
    const float d2 = nearestInGroups(q->groups + args->primID, 1, p, r * r, id);
    if (!(d2 <= r * r) || id == UINT32_MAX) return false;
    q->best = id;
    q->d2 = d2;
    args->query->radius = std::sqrt(d2);
    return true;
}

struct Near {
    const Bounds3* boxes;
    Vec3 lo, hi;
    float reach2;
    std::vector<uint32_t>* out;
    size_t limit;
};

bool groupNear(RTCPointQueryFunctionArguments* args) {
    auto* q = static_cast<Near*>(args->userPtr);
    const Bounds3& box = q->boxes[args->primID];
    const Vec3 gap = max(max(box.lo - q->hi, q->lo - box.hi), Vec3(0.0f));
    if (!(dot(gap, gap) <= q->reach2)) return false;
    q->out->push_back(args->primID);
    if (q->out->size() <= q->limit) return false;  // the sphere stays as it is
    args->query->radius = 0;                       // too many: the search ends
    return true;
}

}  // namespace

bool LaneBvh::near(Vec3 lo, Vec3 hi, float reach, std::vector<uint32_t>& out, size_t limit) const {
    if (m_groups.empty()) return true;
    // The sphere about the box's centre that holds the box grown by `reach` (and rounding).
    RTCPointQuery pq =
        pointQueryAt((lo + hi) * 0.5f, (length(hi - lo) * 0.5f + reach) * (1 + 1e-6f));
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    const size_t before = out.size();
    Near q{m_boxes.data(), lo, hi, reach * reach, &out, before + limit};
    rtcPointQuery(m_scene, &pq, &ctx, groupNear, &q);
    return out.size() - before <= limit;
}

LaneBvh::LaneBvh(const TriangleLanes& lanes) : m_groups(lanes.groups()) {
    // Each group's box, the union of its lanes' boxes: for the build and for near().
    m_boxes.resize(m_groups.size());
    for (size_t i = 0; i < m_groups.size(); ++i) {
        const LaneGroup& g = m_groups[i];
        for (int l = 0; l < kLanes; ++l) {
            m_boxes[i].include(Vec3(g.f[kLox][l], g.f[kLoy][l], g.f[kLoz][l]));
            m_boxes[i].include(Vec3(g.f[kHix][l], g.f[kHiy][l], g.f[kHiz][l]));
        }
    }
    m_scene = rtcNewScene(embreeDevice());
    rtcSetSceneBuildQuality(m_scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = rtcNewGeometry(embreeDevice(), RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geom, static_cast<unsigned>(m_groups.size()));
    rtcSetGeometryUserData(geom, m_boxes.data());
    rtcSetGeometryBoundsFunction(geom, groupBounds, nullptr);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(m_scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(m_scene);
}

LaneBvh::~LaneBvh() {
    if (m_scene) rtcReleaseScene(m_scene);
}

uint32_t LaneBvh::closest(Vec3 p, float radius, float& d2) const {
    RTCPointQuery pq = pointQueryAt(p, radius);
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    Query q{m_groups.data()};
    if (!m_groups.empty()) rtcPointQuery(m_scene, &pq, &ctx, groupClosest, &q);
    d2 = q.d2;
    return q.best;
}

}  // namespace sdft
