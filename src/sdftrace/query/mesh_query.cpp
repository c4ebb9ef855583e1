#include "sdftrace/query/mesh_query.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <mutex>
#include <type_traits>
#include <unordered_map>

#include "sdftrace/bake/closing_film.h"
#include "sdftrace/bake/lbvh.h"
#include "sdftrace/bake/mesh_bvh.h"
#include "sdftrace/bake/winding_number.h"
#include "sdftrace/bake/winding_packet.h"
#include "sdftrace/bake/winding_sign.h"
#include "sdftrace/core/error.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/query/lane_bvh.h"
#include "sdftrace/query/triangle_closest.h"
#include "sdftrace/query/triangle_lanes.h"

namespace sdft {

bool parseMeshSign(const std::string& name, MeshSign& out) {
    if (name == "winding")
        out = MeshSign::Winding;
    else if (name == "parity")
        out = MeshSign::Parity;
    else if (name == "pseudonormal")
        out = MeshSign::PseudoNormal;
    else
        return false;
    return true;
}

namespace {

Vec3 toFloat(Vec3d v) {
    return Vec3(static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z));
}
Vec3d unit(Vec3d v) {
    const double l = norm(v);
    return l > 0 ? v * (1 / l) : Vec3d{};
}

// Points in a chunk (Morton-sorted together: the more, the nearer each point's predecessor and the
// tighter its search bound): 8 MiB of sort keys.
constexpr size_t kChunk = size_t{1} << 20;
// Points a task walks in Morton order, each search bounded by its predecessor's answer.
constexpr size_t kRun = 256;
// Neighbours in Morton order that share one search for their candidate triangles.
constexpr size_t kCluster = 16;
// More lane groups than this within reach of a cluster (sixteen a point: a fine mesh, flat faces
// seen from afar, points far apart): its quarters search for their own candidates, and a quarter
// with more still searches point by point, each point within its own bound, where the shell of
// candidates is as thin as the bound is tight. (Measured
// with the groups' boxes filtering each point's candidates: 256 took 8-17 % fewer instructions
// than 96 on bunny_npm, the elephant and the Stanford bunny, the same on the thin part; 512 no
// fewer.)
constexpr size_t kCandidateGroups = 256;
// Above this many candidate groups, a cluster's points take theirs by the groups' boxes first,
// eight points a box test (groupsWithinBounds); fewer are measured by every point.
constexpr size_t kFilterGroups = 6;
// Clusters after a failed whole-cluster search that go straight to their quarters (doubling with
// each failure in a row).
constexpr int kSoloClusters = 8;
constexpr size_t kQuarter = kCluster / 4;  // the points of a cluster's quarter
// Rim loops beyond which an open mesh's hierarchical sums estimate its winding number faster
// than its films' Taylor models and sums do: between 61 and 106 loops on the meshes measured
// (docs/performance.md).
constexpr size_t kManyLoops = 64;

}  // namespace

struct MeshQuery::Impl {
    std::vector<Vec3d> vertices;
    std::vector<std::array<uint32_t, 3>> faces;
    Vec3d lo, hi, origin;  // origin: the box's centre, which the float copy is relative to
    double diagonal = 0;
    TriangleMesh local;     // float, relative to origin, the faces as given
    float localExtent = 0;  // the largest |coordinate| of `local`
    std::unique_ptr<MeshBvh> bvh;
    std::unique_ptr<TriangleLanes> lanes;
    LbvhFrame frame{};                 // of `local`: the Morton order of the points
    std::unique_ptr<LaneBvh> laneBvh;  // over lanes' groups: one-point searches

    // Winding: the welded, cleaned mesh, its films and the closed mesh's winding tree.
    mutable std::once_flag windingOnce;
    mutable TriangleMesh cleaned;
    mutable std::unique_ptr<ClosingFilm> film;
    mutable std::unique_ptr<WindingNumber> closedWinding;
    mutable std::unique_ptr<WindingNumber> openWinding;  // of the open mesh itself (films exist)
    // So many rim loops that the mesh's own hierarchical sums estimate w_M faster than the films.
    mutable bool manyFilms = false;

    // Pseudonormals: per face, its unit normal, its edges' (ab, bc, ca) and its corners'.
    mutable std::once_flag normalsOnce;
    mutable std::vector<Vec3d> faceNormal, edgeNormal, cornerNormal;
    mutable bool watertight = false;

    Vec3 toLocal(Vec3d p) const { return toFloat(p - origin); }

    // Sort keys and their radix buffer, kept between calls: fresh ones cost a page fault per
    // 4 KiB, thousands a call (15 % of a million-point query of a small mesh on this project's
    // VM). A call leases a pair (made where none is free) and gives it back at its end: as many
    // pairs as calls ever ran at once, each of at most a chunk.
    struct Keys {
        std::unique_ptr<uint64_t[]> order, spare;  // not value-initialized: written before read
        size_t size = 0;
    };
    mutable std::mutex keysMutex;
    mutable std::vector<Keys> keysPool;
    class KeysLease {
      public:
        KeysLease(const Impl& m, size_t n) : m_impl(m) {
            {
                std::lock_guard<std::mutex> lock(m.keysMutex);
                if (!m.keysPool.empty()) {
                    m_keys = std::move(m.keysPool.back());
                    m.keysPool.pop_back();
                }
            }
            if (m_keys.size < n) {
                m_keys.order.reset(new uint64_t[n]);
                m_keys.spare.reset(new uint64_t[n]);
                m_keys.size = n;
            }
        }
        ~KeysLease() {
            std::lock_guard<std::mutex> lock(m_impl.keysMutex);
            m_impl.keysPool.push_back(std::move(m_keys));
        }
        KeysLease(const KeysLease&) = delete;
        KeysLease& operator=(const KeysLease&) = delete;
        uint64_t* order() const { return m_keys.order.get(); }
        uint64_t* spare() const { return m_keys.spare.get(); }

      private:
        const Impl& m_impl;
        Keys m_keys;
    };

    void buildWinding() const {
        std::call_once(windingOnce, [this] {
            MeshReport report;
            cleaned = cleanMesh(local.positions, local.triangles, report);
            if (cleaned.triangles.empty()) return;  // all zero-area: nothing is inside
            film = std::make_unique<ClosingFilm>(cleaned);
            closedWinding = std::make_unique<WindingNumber>(film->closedMesh());
            if (!film->empty()) openWinding = std::make_unique<WindingNumber>(cleaned);
            manyFilms = film->components() > kManyLoops;
        });
    }
    void buildNormals() const;
    struct SignWalk;

    // The double-precision answer at p on face f (the float searches pick the face).
    Closest refine(Vec3d p, uint32_t f) const {
        const auto& t = faces[f];
        const TriangleClosest tc =
            closestOnTriangle(p, vertices[t[0]], vertices[t[1]], vertices[t[2]]);
        Closest r;
        r.distance = norm(p - tc.point);
        r.point = tc.point;
        r.face = f;
        std::copy(tc.bary, tc.bary + 3, r.bary);
        r.feature = tc.feature;
        return r;
    }

    struct ClusterScratch {
        std::vector<uint32_t> ids, winners;  // lane groups
        std::vector<uint32_t> rest;          // ids less winners
        std::vector<uint32_t> within;        // per point, the rest within its bound
        int solo = 0;                        // clusters still to search by quarters
        int failures = 0;                    // clusters in a row with too many candidates
    };
    void closestCluster(const MeshQuery& query, const Vec3d* p, size_t n, Closest* out,
                        ClusterScratch& scratch) const;
    // A cluster's point in the float frame and its nearest face among the previous cluster's
    // (squared distance `known`, face knownId), the float test's error, and the bound they give.
    struct ClusterPoint {
        Vec3 q;
        float known, slack, bound;
        uint32_t knownId;
    };
    // The nearer of c's known face and the nearest of the `count` groups `list` names.
    Closest nearestCandidate(Vec3d p, const ClusterPoint& c, const uint32_t* list,
                             size_t count) const;
    // The answers of n points of a cluster from one search of the groups within reach of their
    // box: false (nothing answered) where those are more than kCandidateGroups.
    bool answerFromCandidates(const Vec3d* p, const ClusterPoint* c, size_t n, Closest* out,
                              ClusterScratch& s) const;

    // The hierarchical tiers of an open mesh's own winding number: `coarse` (beta 1.5, trusted
    // to 0.3), then `fine` (the tree's beta 3, to 0.1), each taken where it is clearly off 1/2
    // (the margins inside() decides by). True with the value and its error; false where neither
    // decides and the films must.
    template <class Coarse, class Fine>
    static bool hierarchicalWinding(Coarse coarse, Fine fine, double& w, double& error) {
        w = coarse();
        if (std::fabs(w - 0.5) > 0.3) {
            error = 0.3;
            return true;
        }
        w = fine();
        if (std::fabs(w - 0.5) > 0.1) {
            error = 0.1;
            return true;
        }
        return false;
    }
    // An open mesh's own winding number at local point q with a bound on its error: the
    // hierarchical tiers, else the films' (closing_film.h).
    double openWindingEstimate(Vec3 q, double& error) const {
        double w;
        if (hierarchicalWinding([&] { return openWinding->fast(q, 1.5); },
                                [&] { return openWinding->fast(q); }, w, error))
            return w;
        const WindingSign::Carried c = WindingSign(*film, *closedWinding).evaluate(q);
        error = c.error;
        return c.winding;
    }
};

// Angle-weighted pseudonormals (Baerentzen and Aanaes 2005, "Signed distance computation using
// the angle weighted pseudonormal"): vertices welded by position, a vertex's normal the sum of its
// faces' unit normals weighted by their angles there, an edge's the sum of its faces' normals.
void MeshQuery::Impl::buildNormals() const {
    std::call_once(normalsOnce, [this] {
        struct Key {
            double x, y, z;
            bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
        };
        struct KeyHash {
            size_t operator()(const Key& k) const {
                uint64_t h = 0;
                for (double d : {k.x, k.y, k.z}) {
                    uint64_t b;
                    std::memcpy(&b, &d, 8);
                    h = (h ^ b) * 0x9E3779B97F4A7C15ull;
                    h ^= h >> 29;
                }
                return h;
            }
        };
        std::unordered_map<Key, uint32_t, KeyHash> ids;
        std::vector<uint32_t> weld(vertices.size());
        for (size_t i = 0; i < vertices.size(); ++i) {
            const Vec3d& v = vertices[i];
            weld[i] = ids.try_emplace(Key{v.x + 0.0, v.y + 0.0, v.z + 0.0},
                                      static_cast<uint32_t>(ids.size()))
                          .first->second;
        }
        std::vector<Vec3d> vertexNormal(ids.size());
        faceNormal.assign(faces.size(), {});
        struct EdgeUse {
            Vec3d normal;
            int forward = 0, backward = 0;  // uses from the lower to the higher welded id, back
        };
        std::unordered_map<uint64_t, EdgeUse> edges;
        edges.reserve(faces.size() * 2);
        auto edgeKey = [&](uint32_t a, uint32_t b) {
            return (static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
        };
        for (size_t f = 0; f < faces.size(); ++f) {
            const auto& t = faces[f];
            const Vec3d p[3] = {vertices[t[0]], vertices[t[1]], vertices[t[2]]};
            const Vec3d n = unit(cross(p[1] - p[0], p[2] - p[0]));
            faceNormal[f] = n;
            for (int c = 0; c < 3; ++c) {
                const Vec3d e1 = unit(p[(c + 1) % 3] - p[c]), e2 = unit(p[(c + 2) % 3] - p[c]);
                const double angle = std::acos(std::clamp(dot(e1, e2), -1.0, 1.0));
                vertexNormal[weld[t[c]]] = vertexNormal[weld[t[c]]] + n * angle;
                const uint32_t a = weld[t[c]], b = weld[t[(c + 1) % 3]];
                EdgeUse& e = edges[edgeKey(a, b)];
                e.normal = e.normal + n;
                (a < b ? e.forward : e.backward) += 1;
            }
        }
        watertight = !faces.empty();
        for (const auto& [key, e] : edges)
            if (e.forward != 1 || e.backward != 1) watertight = false;
        edgeNormal.assign(faces.size() * 3, {});
        cornerNormal.assign(faces.size() * 3, {});
        for (size_t f = 0; f < faces.size(); ++f)
            for (int c = 0; c < 3; ++c) {
                const uint32_t a = weld[faces[f][c]], b = weld[faces[f][(c + 1) % 3]];
                edgeNormal[3 * f + c] = edges[edgeKey(a, b)].normal;
                cornerNormal[3 * f + c] = vertexNormal[a];
            }
    });
}

MeshQuery::MeshQuery(std::vector<Vec3d> vertices, std::vector<std::array<uint32_t, 3>> faces,
                     const std::string& what)
    : m_impl(std::make_unique<Impl>()) {
    Impl& m = *m_impl;
    if (faces.empty()) throw InputError(what + ": faces: no face; expected at least one");
    if (faces.size() > static_cast<size_t>(kMaxLbvhTriangles))
        throw InputError(what + ": faces: " + std::to_string(faces.size()) + " faces; at most " +
                         std::to_string(kMaxLbvhTriangles) + " are accepted");
    for (size_t f = 0; f < faces.size(); ++f)
        for (int c = 0; c < 3; ++c)
            if (faces[f][c] >= vertices.size())
                throw InputError(what + ": faces: face " + std::to_string(f) + " names vertex " +
                                 std::to_string(faces[f][c]) + "; expected indices in [0, " +
                                 std::to_string(vertices.size()) + ")");
    m.lo = {INFINITY, INFINITY, INFINITY};
    m.hi = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < vertices.size(); ++i) {
        const Vec3d& v = vertices[i];
        if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z) ||
            std::fabs(v.x) > 1e30 || std::fabs(v.y) > 1e30 || std::fabs(v.z) > 1e30)
            throw InputError(what + ": vertices: vertex " + std::to_string(i) +
                             " is not finite or beyond 1e30; expected finite coordinates");
        m.lo = {std::min(m.lo.x, v.x), std::min(m.lo.y, v.y), std::min(m.lo.z, v.z)};
        m.hi = {std::max(m.hi.x, v.x), std::max(m.hi.y, v.y), std::max(m.hi.z, v.z)};
    }
    m.origin = (m.lo + m.hi) * 0.5;
    m.diagonal = norm(m.hi - m.lo);
    // Relative to the centre the float copy keeps 7 digits of the mesh's own size, wherever it is.
    const double half = 0.5 * std::max({m.hi.x - m.lo.x, m.hi.y - m.lo.y, m.hi.z - m.lo.z});
    if (half > 1e18)
        throw InputError(what + ": vertices: the mesh is " + std::to_string(2 * half) +
                         " across; at most 2e18 is accepted");
    m.local.positions.resize(vertices.size());
    for (size_t i = 0; i < vertices.size(); ++i) m.local.positions[i] = m.toLocal(vertices[i]);
    m.local.triangles = faces;
    m.vertices = std::move(vertices);
    m.faces = std::move(faces);
    m.bvh = std::make_unique<MeshBvh>(m.local);
    m.lanes = std::make_unique<TriangleLanes>(m.local);
    m.frame = lbvhFrame(m.local);
    m.laneBvh = std::make_unique<LaneBvh>(*m.lanes);
    for (const Vec3& v : m.local.positions)
        m.localExtent = std::max({m.localExtent, std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
}

MeshQuery::~MeshQuery() = default;

const std::vector<Vec3d>& MeshQuery::vertices() const { return m_impl->vertices; }
const std::vector<std::array<uint32_t, 3>>& MeshQuery::faces() const { return m_impl->faces; }
std::array<Vec3d, 2> MeshQuery::bounds() const { return {m_impl->lo, m_impl->hi}; }
double MeshQuery::diagonal() const { return m_impl->diagonal; }
bool MeshQuery::watertight() const {
    m_impl->buildNormals();
    return m_impl->watertight;
}

void MeshQuery::prepare(MeshSign sign) const {
    if (sign == MeshSign::Winding) m_impl->buildWinding();
    if (sign == MeshSign::PseudoNormal) m_impl->buildNormals();
}

MeshQuery::Closest MeshQuery::closest(Vec3d p) const { return closest(p, INFINITY); }

MeshQuery::Closest MeshQuery::closest(Vec3d p, double bound) const {
    const Impl& m = *m_impl;
    const Vec3 q = m.toLocal(p);
    uint32_t face = UINT32_MAX;
    float d2;
    if (std::isfinite(bound)) {
        // Widened past float rounding of the point, the vertices and the bound itself.
        const double radius =
            std::fmin(bound * (1 + 1e-5) + 1e-6 * m.diagonal + 1e-30, 3.0e38);  // a float
        face = m.laneBvh->closest(q, static_cast<float>(radius), d2);
    }
    if (face == UINT32_MAX) face = m.laneBvh->closest(q, INFINITY, d2);
    if (face == UINT32_MAX) {  // unreachable for finite points; kept total
        Closest r;
        r.distance = INFINITY;
        return r;
    }
    return m.refine(p, face);
}

// The closest answers of n <= kCluster neighbouring points: their upper bounds from the previous
// cluster's faces (1-Lipschitz), the candidates for all of them from one BVH traversal about
// their box (or, where those are too many, for each quarter of them), then each point's nearest
// candidate by the lane test (triangle_lanes.h). The groups the bounds came from are not measured
// again: a point's nearest is the nearer of its nearest among them and among the other candidates
// (every triangle within its bound is a candidate).
void MeshQuery::Impl::closestCluster(const MeshQuery& query, const Vec3d* p, size_t n, Closest* out,
                                     ClusterScratch& s) const {
    ClusterPoint c[kCluster];
    if (s.winners.empty()) s.winners.push_back(lanes->groupOf(query.closest(p[0]).face));
    for (size_t i = 0; i < n; ++i) {
        c[i].q = toLocal(p[i]);
        c[i].knownId = UINT32_MAX;
        c[i].known = nearestInGroupList(lanes->groups().data(), s.winners.data(), s.winners.size(),
                                        c[i].q, INFINITY, c[i].knownId);
        // Widened past the float test's rounding, which grows with the coordinates.
        const float far =
            std::max({localExtent, std::fabs(c[i].q.x), std::fabs(c[i].q.y), std::fabs(c[i].q.z)});
        c[i].slack = 1e-5f * std::sqrt(c[i].known) + 4e-6f * far;
        c[i].bound = std::sqrt(c[i].known) + c[i].slack;
    }
    bool answered = false;
    if (s.solo > 0) {
        --s.solo;
    } else {
        answered = answerFromCandidates(p, c, n, out, s);
        // Each failure in a row doubles the clusters that skip the whole cluster's search.
        s.solo = answered ? 0 : kSoloClusters << std::min(s.failures++, 5);
        if (answered) s.failures = 0;
    }
    // Too many candidates for the cluster (a fine mesh, flat faces seen from afar): quarters of
    // it search on their own, their boxes smaller; a quarter with too many still, point by point.
    for (size_t first = 0; !answered && first < n; first += kQuarter) {
        const size_t m = std::min(kQuarter, n - first);
        if (!answerFromCandidates(p + first, c + first, m, out + first, s))
            for (size_t i = first; i < first + m; ++i) out[i] = query.closest(p[i], c[i].bound);
    }
    s.winners.clear();
    for (size_t i = 0; i < n; ++i) s.winners.push_back(lanes->groupOf(out[i].face));
    std::sort(s.winners.begin(), s.winners.end());
    s.winners.erase(std::unique(s.winners.begin(), s.winners.end()), s.winners.end());
}

bool MeshQuery::Impl::answerFromCandidates(const Vec3d* p, const ClusterPoint* c, size_t n,
                                           Closest* out, ClusterScratch& s) const {
    Vec3 lo(INFINITY), hi(-INFINITY);
    float reach = 0;
    for (size_t i = 0; i < n; ++i) {
        lo = min(lo, c[i].q);
        hi = max(hi, c[i].q);
        reach = std::max(reach, c[i].bound);
    }
    s.ids.clear();
    if (!std::isfinite(reach) || !laneBvh->near(lo, hi, reach, s.ids, kCandidateGroups) ||
        s.ids.empty())
        return false;
    s.rest.clear();
    for (const uint32_t g : s.ids)
        if (!std::binary_search(s.winners.begin(), s.winners.end(), g)) s.rest.push_back(g);
    const size_t count = s.rest.size();
    if (count <= kFilterGroups) {
        for (size_t i = 0; i < n; ++i) out[i] = nearestCandidate(p[i], c[i], s.rest.data(), count);
        return true;
    }
    Vec3 q[kCluster];
    float bound2[kCluster];
    uint32_t within[kCluster];
    for (size_t i = 0; i < n; ++i) {
        q[i] = c[i].q;
        bound2[i] = c[i].bound * c[i].bound;
    }
    s.within.resize(n * count);
    groupsWithinBounds(laneBvh->boxes().data(), s.rest.data(), count, q, bound2, n, s.within.data(),
                       within);
    for (size_t i = 0; i < n; ++i)
        out[i] = nearestCandidate(p[i], c[i], s.within.data() + i * count, within[i]);
    return true;
}

MeshQuery::Closest MeshQuery::Impl::nearestCandidate(Vec3d p, const ClusterPoint& c,
                                                     const uint32_t* list, size_t count) const {
    uint32_t other = UINT32_MAX;
    const float d2 = count == 0 ? INFINITY
                                : nearestInGroupList(lanes->groups().data(), list, count, c.q,
                                                     c.bound * c.bound, other);
    Closest best = refine(p, d2 < c.known ? other : c.knownId);
    // Within the float test's error of each other: the nearer in double.
    if (other != UINT32_MAX && std::fabs(std::sqrt(d2) - std::sqrt(c.known)) <= 2 * c.slack) {
        const Closest second = refine(p, d2 < c.known ? c.knownId : other);
        if (second.distance < best.distance) best = second;
    }
    return best;
}

double MeshQuery::windingNumber(Vec3d p) const {
    m_impl->buildWinding();
    if (!m_impl->closedWinding) return 0;
    return WindingSign(*m_impl->film, *m_impl->closedWinding).winding(m_impl->toLocal(p));
}

bool MeshQuery::inside(Vec3d p, MeshSign sign, const Closest* known) const {
    const Impl& m = *m_impl;
    switch (sign) {
        case MeshSign::Winding: {
            m.buildWinding();
            if (!m.closedWinding) return false;
            const Vec3 q = m.toLocal(p);
            if (m.openWinding) {
                // An open mesh: its own hierarchical winding number decides wherever it is clearly
                // off 1/2 (first-order dipoles err by under 2.5 % at beta 3, winding_number.h),
                // which is all but the points near a hole; those go through the films.
                double error;
                return m.openWindingEstimate(q, error) > 0.5;
            }
            return WindingSign(*m.film, *m.closedWinding).evaluate(q).inside();
        }
        case MeshSign::Parity:
            return m.bvh->insideByParity(m.toLocal(p));
        case MeshSign::PseudoNormal: {
            m.buildNormals();
            const Closest c = known ? *known : closest(p);
            const size_t f = c.face;
            Vec3d n;
            if (c.feature < 3)
                n = m.cornerNormal[3 * f + c.feature];
            else if (c.feature < 6)
                n = m.edgeNormal[3 * f + (c.feature - 3)];
            else
                n = m.faceNormal[f];
            return dot(p - c.point, n) < 0;
        }
    }
    return false;
}

MeshQuery::Hit MeshQuery::rayCast(Vec3d origin, Vec3d direction, double tMax) const {
    return rayCast(origin, direction, tMax, true);
}

MeshQuery::Hit MeshQuery::rayCast(Vec3d origin, Vec3d direction, double tMax, bool refine) const {
    const Impl& m = *m_impl;
    Hit h;
    const float tfar = static_cast<float>(std::fmin(tMax, 3.0e38));
    const MeshBvh::Hit e = m.bvh->firstHit({m.toLocal(origin), toFloat(direction)}, 0, tfar);
    if (!std::isfinite(e.t)) return h;
    if (!refine) {
        // Embree's float answer as it is (the mesh's frame is a translation of the caller's):
        // no look at the face's vertices, whose cache misses cost more than the traversal.
        h.face = e.triangle;
        h.normal = unit(toDouble(e.normal));
        h.t = e.t;
        h.u = e.u;
        h.v = e.v;
        return h;
    }
    const auto& t = m.faces[e.triangle];
    const Vec3d a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
    const Vec3d n = cross(b - a, c - a);
    h.face = e.triangle;
    h.normal = unit(n);
    h.t = e.t;
    h.u = e.u;
    h.v = e.v;
    // Refined in double: the plane's t and the hit's barycentrics (Embree found it in float).
    const double denom = dot(n, direction);
    if (std::fabs(denom) > 0) {
        const double t2 = dot(n, a - origin) / denom;
        const Vec3d x = origin + direction * t2;
        const double area2 = dot(n, n);
        const double u = dot(cross(x - a, c - a), n) / area2;  // weight of b
        const double v = dot(cross(b - a, x - a), n) / area2;  // weight of c
        if (std::isfinite(t2) && std::fabs(t2 - e.t) <= 1e-3 * std::fabs(e.t) + 1e-6 * m.diagonal &&
            t2 <= tMax) {
            h.t = std::max(t2, 0.0);
            h.u = u;
            h.v = v;
        }
    }
    return h;
}

namespace {

template <class T>
Vec3d pointAt(const T* xyz, size_t i) {
    return {static_cast<double>(xyz[3 * i]), static_cast<double>(xyz[3 * i + 1]),
            static_cast<double>(xyz[3 * i + 2])};
}

// Keys (Morton code above index) in order of their code's top 20 bits, a cell about 1/100 of
// the box a side: two counting passes of 10 bits (LSD radix), where order within a cell is
// immaterial to the walk.
void sortByCell(uint64_t* keys, uint64_t* spare, size_t n) {
    for (int shift : {42, 52}) {
        size_t start[1025] = {};
        for (size_t i = 0; i < n; ++i) ++start[((keys[i] >> shift) & 1023) + 1];
        for (int b = 0; b < 1024; ++b) start[b + 1] += start[b];
        for (size_t i = 0; i < n; ++i) spare[start[(keys[i] >> shift) & 1023]++] = keys[i];
        std::swap(keys, spare);
    }
    // An even number of passes: the sorted keys are back in the caller's `keys`.
}

template <class T>
void checkFinite(const T* xyz, size_t n, const char* what) {
    std::atomic<size_t> bad{SIZE_MAX};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 14), [&](const auto& r) {
        for (size_t i = r.begin(); i != r.end(); ++i)
            for (int k = 0; k < 3; ++k)
                if (!std::isfinite(xyz[3 * i + k]) || std::fabs(xyz[3 * i + k]) > T(1e30)) {
                    size_t cur = bad.load();
                    while (i < cur && !bad.compare_exchange_weak(cur, i)) {
                    }
                }
    });
    if (const size_t i = bad.load(); i != SIZE_MAX)
        throw InputError(std::string(what) + ": row " + std::to_string(i) +
                         " is not finite or beyond 1e30; expected finite coordinates");
}

}  // namespace

// The signs of a run of points in Morton order (one task's): each decided from scratch by
// inside(), or carried from the previous point where no surface can lie between them.
struct MeshQuery::Impl::SignWalk {
    const MeshQuery& query;
    const Impl& m;
    MeshSign sign;
    bool carry;      // a closed mesh: its winding number carried between neighbours
    bool carryOpen;  // an open mesh: W of it closed by its films carried, w_M = W - w_F bounded

    bool havePrev = false;
    Vec3d prevP{};
    double prevD = 0;
    int winding = 0;  // a closed mesh's, at the previous point
    // An open mesh's (winding_sign.h): W exact, w_M within its error; valid once `haveCarried`.
    WindingSign::Carried carried{};
    bool haveCarried = false;
    // Over the box of a cluster's points and the point before them (so every step between them):
    // the bound on |grad w_M| (closing_film.h) and the film triangles a step may cross.
    double clusterGradient = INFINITY;
    std::vector<uint32_t> films{};
    float filmEps = 0;
    // A Taylor model of the films' winding number about the box's centre (closing_film.h), made
    // where a carry first runs out and no film meets the box: it bounds w_F at every point in it
    // by the distance to the centre squared, far less than the path walked from the last sum.
    Vec3 centre{};
    float half = 0;
    bool haveModel = false;
    ClosingFilm::Taylor model{};
    // The cluster's points and their coarse and fine hierarchical w_M, eight at a time where the
    // films are many (neighbours walk the tree together, winding_packet.h, far terms in float).
    const Vec3d* cluster = nullptr;
    size_t clusterSize = 0;
    uint32_t haveCoarse = 0, haveFine = 0;
    double coarse[kCluster] = {}, fine[kCluster] = {};

    void beginCluster(const Vec3d* p, size_t n) {
        if (!carryOpen) return;
        cluster = p;
        clusterSize = n;
        haveCoarse = haveFine = 0;
        Vec3 lo = m.toLocal(havePrev ? prevP : p[0]), hi = lo;
        for (size_t j = 0; j < n; ++j) {
            const Vec3 q = m.toLocal(p[j]);
            lo = min(lo, q);
            hi = max(hi, q);
        }
        clusterGradient = m.film->gradientBound(lo, hi);
        centre = (lo + hi) * 0.5f;
        half = 0.5f * length(hi - lo) * 1.0001f;
        haveModel = false;
        // Past the float rounding of the points and of the film's planes.
        filmEps = 1e-6f * std::max({m.localExtent, maxComponent(abs(lo)), maxComponent(abs(hi))});
        m.film->trianglesNear(lo, hi, filmEps, films);
    }

    // An open mesh's winding numbers at p, the j-th point of the cluster begun: W changes by the
    // signed crossings of the mesh (none where the two points' balls overlap, else counted along
    // the step) and of the films near the cluster; w_M by the mesh's crossings and by at most the
    // gradient bound times the step. Where that leaves its side of 1/2 unsure, w_M is estimated
    // again (estimate()); everything is evaluated from scratch where a crossing is too near an
    // edge to count.
    void carryWinding(Vec3d p, size_t j, const Closest& c) {
        const Vec3 q = m.toLocal(p);
        if (haveCarried && havePrev) {
            const Vec3 from = m.toLocal(prevP);
            const double step = norm(p - prevP);
            int meshChange = 0, filmChange = 0;
            bool counted =
                step < 0.999 * (c.distance + prevD) || m.bvh->windingChange(from, q, meshChange);
            for (size_t k = 0; counted && k < films.size(); ++k) {
                const Crossing x =
                    segmentCrossing(from, q, m.film->filmTriangles()[films[k]], filmEps);
                counted = x != Crossing::Undecided;
                filmChange += x == Crossing::Enter ? 1 : x == Crossing::Leave ? -1 : 0;
            }
            if (counted) {
                carried = {carried.closed + meshChange + filmChange,
                           carried.winding + static_cast<float>(meshChange),
                           carried.error + static_cast<float>(clusterGradient * step * 1.001)};
                if (!carried.decided()) estimate(q, j);
                return;
            }
        }
        carried = WindingSign(*m.film, *m.closedWinding).evaluate(q);
        haveCarried = true;
    }

    // A new w_M at q with W known, by the cheapest that decides: few films, their Taylor model
    // about the cluster's centre, else their sums at q; many, the hierarchical sums of the mesh
    // itself (coarse, then fine), else the films' sums at q.
    void estimate(Vec3 q, size_t j) {
        if (m.manyFilms) {
            double w, error;
            if (Impl::hierarchicalWinding([&] { return coarseAt(j); }, [&] { return fineAt(j); }, w,
                                          error)) {
                carried = {carried.closed, static_cast<float>(w), static_cast<float>(error)};
                return;
            }
        } else {
            fromModel(q);
            if (carried.decided()) return;
        }
        carried = WindingSign::refresh(*m.film, q, carried.closed);
    }

    // w_M at q as W less the cluster's model of w_F, where that is the closer bound.
    void fromModel(Vec3 q) {
        if (!films.empty() || !std::isfinite(clusterGradient)) return;
        if (!haveModel) {
            model = m.film->taylor(centre, half);
            haveModel = true;
        }
        if (!model.valid) return;
        const Vec3 d = q - centre;
        const float error = model.error + model.quadratic * dot(d, d);
        if (error < carried.error)
            carried = {carried.closed,
                       static_cast<float>(carried.closed) - (model.value + dot(model.gradient, d)),
                       error};
    }

    // The coarse winding number of the cluster's j-th point, with those of the next seven.
    double coarseAt(size_t j) {
        if (!((haveCoarse >> j) & 1u)) haveCoarse |= row(j, ~0u, 1.5, coarse);
        return coarse[j];
    }
    // The fine one, with those of the next seven whose coarse ones will not do.
    double fineAt(size_t j) {
        if (!((haveFine >> j) & 1u)) {
            uint32_t wanted = 1;
            for (size_t i = j + 1; i < std::min(j + kRow, clusterSize); ++i)
                if (((haveCoarse >> i) & 1u) && !((haveFine >> i) & 1u) &&
                    std::fabs(coarse[i] - 0.5) <= 0.3)
                    wanted |= 1u << (i - j);
            haveFine |= row(j, wanted, m.openWinding->beta(), fine);
        }
        return fine[j];
    }
    static constexpr size_t kRow = 8;  // points to a row (winding_packet.h's packet)
    uint32_t row(size_t j, uint32_t wanted, double beta, double* out) const {
        const size_t k = std::min(kRow, clusterSize - j);
        Vec3 lanes[kRow];
        for (size_t i = 0; i < k; ++i) lanes[i] = m.toLocal(cluster[j + i]);
        wanted &= (1u << k) - 1;
        // Far terms in float: the estimates decide by margins of 0.1 and more.
        windingNumberRowFloat(m.openWinding->view(), lanes, static_cast<int>(k), beta, out + j,
                              wanted);
        return wanted << j;
    }

    // Inside at p, the j-th point of the cluster begun, whose closest answer is c (distance 0
    // when distances are not wanted).
    bool decide(Vec3d p, size_t j, const Closest& c) {
        bool in;
        if (carry) {
            // When the balls of the two distances overlap along the segment from the previous
            // point, no surface lies between them (the exact bakes' rule); else a closed mesh's
            // winding number, an integer, changes by the faces the segment crosses: counted,
            // unless a crossing is too near an edge or an end to count surely.
            const double step = norm(p - prevP);
            const bool clear = havePrev && step < 0.999 * (c.distance + prevD);
            int change = 0;
            if (!clear) {
                if (havePrev && m.bvh->windingChange(m.toLocal(prevP), m.toLocal(p), change))
                    winding += change;
                else if (sign == MeshSign::Winding)
                    winding = static_cast<int>(std::lround(
                        WindingSign(*m.film, *m.closedWinding).evaluate(m.toLocal(p)).winding));
                else
                    winding = query.inside(p, sign, &c);
            }
            in = sign == MeshSign::Parity ? (winding & 1) != 0 : winding > 0;
        } else if (carryOpen) {
            carryWinding(p, j, c);
            in = carried.inside();
        } else {
            in = query.inside(p, sign, &c);
        }
        havePrev = true;
        prevP = p;
        prevD = c.distance;
        return in;
    }
};

template <class T>
void MeshQuery::queryPoints(const T* xyz, size_t n, const PointOutputs& out,
                            const PointOptions& options) const {
    const Impl& m = *m_impl;
    checkFinite(xyz, n, "points");
    const bool wantSign = options.signedDistance || out.inside;
    const bool wantClosest = out.distance || out.closest || out.face || out.bary ||
                             (wantSign && options.sign == MeshSign::PseudoNormal);
    if (wantSign) prepare(options.sign);
    if (out.winding) prepare(MeshSign::Winding);
    // Signs carry between neighbours on closed meshes (winding and parity alike are constant off
    // the surface there); pseudonormals cost nothing extra anyway.
    const bool carry =
        wantSign && wantClosest && options.sign != MeshSign::PseudoNormal && watertight();
    // An open mesh's winding number carries too, within its gradient bound.
    const bool carryOpen =
        wantSign && wantClosest && !carry && options.sign == MeshSign::Winding && m.openWinding;
    auto* distance = static_cast<T*>(out.distance);
    auto* closestOut = static_cast<T*>(out.closest);
    auto* bary = static_cast<T*>(out.bary);
    auto* winding = static_cast<T*>(out.winding);
    Progress progress(options.progress, n, !options.progress.empty());
    // Morton order by the LBVH's keys (bake/lbvh.h) over the mesh's box: code above index.
    const LbvhFrame& frame = m.frame;
    const Impl::KeysLease keys(m, std::min(kChunk, n));
    uint64_t *order = keys.order(), *spare = keys.spare();
    for (size_t first = 0; first < n; first += kChunk) {
        const size_t count = std::min(kChunk, n - first);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 4096), [&](const auto& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                const Vec3 q = m.toLocal(pointAt(xyz, first + i));
                order[i] = lbvhKey(q, q, q, frame.lo, frame.invExtent, static_cast<uint32_t>(i));
            }
        });
        if (wantClosest) sortByCell(order, spare, count);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, count, kRun), [&](const auto& r) {
            Impl::SignWalk signs{*this, m, options.sign, carry, carryOpen};
            Impl::ClusterScratch scratch;
            Vec3d points[kCluster];
            size_t index[kCluster];
            Closest answers[kCluster];
            for (size_t k0 = r.begin(); k0 < r.end(); k0 += kCluster) {
                const size_t n = std::min(kCluster, r.end() - k0);
                for (size_t j = 0; j < n; ++j) {
                    index[j] = first + (order[k0 + j] & 0xFFFFFFFFu);
                    // Morton order reads the points and writes the answers out of order: the
                    // next cluster's are fetched while this one is measured.
                    if (k0 + kCluster + j < r.end()) {
                        const size_t ahead = first + (order[k0 + kCluster + j] & 0xFFFFFFFFu);
                        __builtin_prefetch(xyz + 3 * ahead);
                        if (distance) __builtin_prefetch(distance + ahead, 1);
                    }
                    points[j] = pointAt(xyz, index[j]);
                }
                if (wantClosest) m.closestCluster(*this, points, n, answers, scratch);
                signs.beginCluster(points, n);
                for (size_t j = 0; j < n; ++j) {
                    const size_t i = index[j];
                    const Vec3d& p = points[j];
                    const Closest c = wantClosest ? answers[j] : Closest{};
                    const bool in = wantSign && signs.decide(p, j, c);
                    if (distance)
                        distance[i] =
                            static_cast<T>(options.signedDistance && in ? -c.distance : c.distance);
                    if (closestOut)
                        for (int a = 0; a < 3; ++a)
                            closestOut[3 * i + a] = static_cast<T>(c.point[a]);
                    if (out.face) out.face[i] = c.face;
                    if (bary)
                        for (int a = 0; a < 3; ++a) bary[3 * i + a] = static_cast<T>(c.bary[a]);
                    if (out.inside) out.inside[i] = in;
                    if (winding) winding[i] = static_cast<T>(windingNumber(p));
                }
            }
            progress.advance(r.size());
        });
    }
}

template <class T>
void MeshQuery::castRays(const T* origins, const T* directions, size_t n, double tMax,
                         const RayOutputs& out, const std::string& label) const {
    checkFinite(origins, n, "origins");
    checkFinite(directions, n, "directions");
    auto* t = static_cast<T*>(out.t);
    auto* bary = static_cast<T*>(out.bary);
    auto* normal = static_cast<T*>(out.normal);
    Progress progress(label, n, !label.empty());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const auto& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            // Float rays are answered in float: Embree's own t, barycentrics and normal.
            const Hit h = rayCast(pointAt(origins, i), pointAt(directions, i), tMax,
                                  std::is_same_v<T, double>);
            const bool hit = h.face != UINT32_MAX;
            if (t) t[i] = static_cast<T>(h.t);
            if (out.face) out.face[i] = hit ? static_cast<int64_t>(h.face) : -1;
            if (bary) {
                bary[2 * i] = static_cast<T>(hit ? h.u : 0);
                bary[2 * i + 1] = static_cast<T>(hit ? h.v : 0);
            }
            if (normal)
                for (int a = 0; a < 3; ++a) normal[3 * i + a] = static_cast<T>(h.normal[a]);
        }
        progress.advance(r.size());
    });
}

template void MeshQuery::queryPoints<float>(const float*, size_t, const PointOutputs&,
                                            const PointOptions&) const;
template void MeshQuery::queryPoints<double>(const double*, size_t, const PointOutputs&,
                                             const PointOptions&) const;
template void MeshQuery::castRays<float>(const float*, const float*, size_t, double,
                                         const RayOutputs&, const std::string&) const;
template void MeshQuery::castRays<double>(const double*, const double*, size_t, double,
                                          const RayOutputs&, const std::string&) const;

}  // namespace sdft
