#include "sdftrace/query/lane_bvh.h"

#include <algorithm>
#include <cmath>

#include "sdftrace/bake/embree_device.h"

namespace sdft {

namespace {

// A group's box: the union of its lanes' boxes.
void groupBounds(const RTCBoundsFunctionArguments* args) {
    const auto& groups = *static_cast<const std::vector<LaneGroup>*>(args->geometryUserPtr);
    const LaneGroup& g = groups[args->primID];
    RTCBounds* b = args->bounds_o;
    b->lower_x = *std::min_element(g.f[kLox], g.f[kLox] + kLanes);
    b->lower_y = *std::min_element(g.f[kLoy], g.f[kLoy] + kLanes);
    b->lower_z = *std::min_element(g.f[kLoz], g.f[kLoz] + kLanes);
    b->upper_x = *std::max_element(g.f[kHix], g.f[kHix] + kLanes);
    b->upper_y = *std::max_element(g.f[kHiy], g.f[kHiy] + kLanes);
    b->upper_z = *std::max_element(g.f[kHiz], g.f[kHiz] + kLanes);
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
    const LaneGroup* groups;
    Vec3 lo, hi;
    float reach2;
    std::vector<uint32_t>* out;
    size_t limit;
};

bool groupNear(RTCPointQueryFunctionArguments* args) {
    auto* q = static_cast<Near*>(args->userPtr);
    const LaneGroup& g = q->groups[args->primID];
    Vec3 glo(INFINITY), ghi(-INFINITY);
    for (int l = 0; l < kLanes; ++l) {
        glo = min(glo, Vec3(g.f[kLox][l], g.f[kLoy][l], g.f[kLoz][l]));
        ghi = max(ghi, Vec3(g.f[kHix][l], g.f[kHiy][l], g.f[kHiz][l]));
    }
    const Vec3 gap = max(max(glo - q->hi, q->lo - ghi), Vec3(0.0f));
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
    Near q{m_groups.data(), lo, hi, reach * reach, &out, before + limit};
    rtcPointQuery(m_scene, &pq, &ctx, groupNear, &q);
    return out.size() - before <= limit;
}

LaneBvh::LaneBvh(const TriangleLanes& lanes) : m_groups(lanes.groups()) {
    m_scene = rtcNewScene(embreeDevice());
    rtcSetSceneBuildQuality(m_scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = rtcNewGeometry(embreeDevice(), RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geom, static_cast<unsigned>(m_groups.size()));
    rtcSetGeometryUserData(geom, const_cast<std::vector<LaneGroup>*>(&m_groups));
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
