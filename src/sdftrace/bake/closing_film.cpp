#include "sdftrace/bake/closing_film.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "sdftrace/bake/winding_number.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/math/ray.h"

namespace sdft {

namespace {
constexpr double kFourPi = 12.566370614359172;

uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
}
}  // namespace

ClosingFilm::ClosingFilm(const TriangleMesh& mesh) : m_source(&mesh) {
    // The boundary chain: per undirected edge (a < b), the count of a -> b minus that of b -> a
    // (sorted keys, the direction in the lowest bit).
    SDFT_CHECK(mesh.positions.size() < (size_t(1) << 31));
    std::vector<uint64_t> keys;
    keys.reserve(3 * mesh.triangles.size());
    for (const auto& t : mesh.triangles)
        for (int e = 0; e < 3; ++e) {
            uint64_t a = t[e], b = t[(e + 1) % 3];
            keys.push_back(a < b ? (a << 33 | b << 1) : (b << 33 | a << 1 | 1));
        }
    std::sort(keys.begin(), keys.end());
    std::vector<std::pair<uint32_t, uint32_t>> rim;  // directed boundary edges, with multiplicity
    for (size_t n = 0; n < keys.size();) {
        size_t m = n;
        int count = 0;
        for (; m < keys.size() && keys[m] >> 1 == keys[n] >> 1; ++m) count += keys[m] & 1 ? -1 : 1;
        auto a = static_cast<uint32_t>(keys[n] >> 33), b = static_cast<uint32_t>(keys[n] >> 1);
        for (int c = 0; c < std::abs(count); ++c)
            rim.push_back(count > 0 ? std::make_pair(a, b) : std::make_pair(b, a));
        n = m;
    }
    if (rim.empty()) return;
    keys = std::vector<uint64_t>();
    m_closed = mesh;

    // Connected pieces of the rim (each is itself a cycle: every vertex has as many edges in as
    // out), one apex each at the mean of its vertices.
    std::vector<uint32_t> parent(mesh.positions.size());
    std::iota(parent.begin(), parent.end(), 0u);
    for (auto [a, b] : rim) parent[findRoot(parent, a)] = findRoot(parent, b);
    std::map<uint32_t, std::vector<std::pair<uint32_t, uint32_t>>> pieces;
    for (auto e : rim) pieces[findRoot(parent, e.first)].push_back(e);
    for (const auto& [root, edges] : pieces) {
        double sum[3] = {0, 0, 0};
        for (auto [a, b] : edges) {
            sum[0] += mesh.positions[a].x, sum[1] += mesh.positions[a].y,
                sum[2] += mesh.positions[a].z;
        }
        Vec3 apex(static_cast<float>(sum[0] / edges.size()),
                  static_cast<float>(sum[1] / edges.size()),
                  static_cast<float>(sum[2] / edges.size()));
        const auto apexIndex = static_cast<uint32_t>(m_closed.positions.size());
        m_closed.positions.push_back(apex);
        m_cones.push_back({apex, m_films.size(), edges.size(), -1});
        for (auto [a, b] : edges) {
            // Against the rim edge a -> b: the cone's boundary then cancels M's.
            Vec3 pa = mesh.positions[a], pb = mesh.positions[b];
            m_closed.triangles.push_back({apexIndex, b, a});
            m_films.emplace_back(apex, pb, pa);
            m_cones.back().area += 0.5f * m_films.back().area2 * 1.0001f;
            m_cones.back().radius = std::max(
                m_cones.back().radius, std::max(length(pa - apex), length(pb - apex)) * 1.0001f);
            m_edges.push_back({pa, pb});
            for (int d = 0; d < 3; ++d) {
                m_corners[d].push_back(pb[d]);
                m_corners[3 + d].push_back(pa[d]);
            }
        }
    }
    for (Cone& cone : m_cones)
        cone.root = build(static_cast<int>(cone.first), static_cast<int>(cone.count));
    // Every rim piece has its cone, so there is at least one here.
    std::vector<int> cones(m_cones.size());
    std::iota(cones.begin(), cones.end(), 0);
    if (!cones.empty()) buildGroups(cones.data(), static_cast<int>(cones.size()));
}

int ClosingFilm::buildGroups(int* cones, int count) {
    const int index = static_cast<int>(m_groups.size());
    m_groups.emplace_back();
    Group g;
    Bounds3 box;
    for (int i = 0; i < count; ++i) {
        const Node& root = m_nodes[m_cones[cones[i]].root];
        box.include(root.centre - Vec3(root.radius));
        box.include(root.centre + Vec3(root.radius));
    }
    g.centre = (box.lo + box.hi) * 0.5f;
    for (int i = 0; i < count; ++i) {
        const Node& root = m_nodes[m_cones[cones[i]].root];
        g.radius = std::fmax(g.radius, length(root.centre - g.centre) + root.radius);
        g.length += root.length;
        g.lengthRadius += root.length * root.radius;
        g.area += m_cones[cones[i]].area;
    }
    g.radius *= 1.0001f;
    g.length *= 1.0001f;
    g.lengthRadius *= 1.0001f;
    g.area *= 1.0001f;
    if (count == 1) {
        g.cone = cones[0];
    } else {
        const Vec3 ext = box.extent();
        const int axis = ext.x > ext.y ? (ext.x > ext.z ? 0 : 2) : (ext.y > ext.z ? 1 : 2);
        const int mid = count / 2;
        std::nth_element(cones, cones + mid, cones + count, [&](int x, int y) {
            return m_nodes[m_cones[x].root].centre[axis] < m_nodes[m_cones[y].root].centre[axis];
        });
        g.left = buildGroups(cones, mid);
        g.right = buildGroups(cones + mid, count - mid);
    }
    m_groups[index] = g;
    return index;
}

int ClosingFilm::build(int first, int count) {
    const int index = static_cast<int>(m_nodes.size());
    m_nodes.emplace_back();
    Node n;
    n.first = first;
    n.count = count;
    Bounds3 box;
    for (int e = first; e < first + count; ++e) {
        box.include(m_edges[e].a);
        box.include(m_edges[e].b);
        n.length += length(m_edges[e].b - m_edges[e].a);
    }
    n.centre = (box.lo + box.hi) * 0.5f;
    for (int e = first; e < first + count; ++e)
        n.radius = std::fmax(
            n.radius, std::fmax(length(m_edges[e].a - n.centre), length(m_edges[e].b - n.centre)));
    // Above the rounding of the lengths: the bound stays conservative.
    n.radius *= 1.0001f;
    n.length *= 1.0001f;
    constexpr int kLeafEdges = 4;
    if (count > kLeafEdges) {
        Vec3 ext = box.extent();
        int axis = ext.x > ext.y ? (ext.x > ext.z ? 0 : 2) : (ext.y > ext.z ? 1 : 2);
        int mid = first + count / 2;
        std::nth_element(m_edges.begin() + first, m_edges.begin() + mid,
                         m_edges.begin() + first + count, [&](const Edge& x, const Edge& y) {
                             return x.a[axis] + x.b[axis] < y.a[axis] + y.b[axis];
                         });
        n.left = build(first, mid - first);
        n.right = build(mid, first + count - mid);
    }
    m_nodes[index] = n;
    return index;
}

namespace {
double pointSegmentDistance(Vec3 p, Vec3 a, Vec3 b) {
    Vec3 ab = b - a;
    float t = dot(ab, ab) > 0 ? std::clamp(dot(p - a, ab) / dot(ab, ab), 0.0f, 1.0f) : 0.0f;
    return length(p - (a + ab * t));
}
}  // namespace

double ClosingFilm::winding(Vec3 p) const {
    double sum = 0;
    for (const auto& t : m_films) sum += triangleSolidAngle(p, t.a, t.b, t.c);
    return sum / kFourPi;
}

float ClosingFilm::windingFast(Vec3 p, float* slack) const {
    float sum = 0;
    for (const Cone& cone : m_cones) {
        if (slack) {
            const float gap = length(cone.apex - p) - cone.radius;
            if (gap > cone.radius) {
                const float bound = cone.area / (static_cast<float>(kFourPi) * gap * gap) * 1.001f;
                if (bound < 0.01f) {
                    *slack += bound;
                    continue;
                }
            }
        }
        sum += coneWinding(cone, p);
    }
    return sum * static_cast<float>(2.0 / kFourPi);
}

float ClosingFilm::coneWinding(const Cone& cone, Vec3 p) const {
    // Van Oosterom & Strackee as in triangleSolidAngle, in float, the apex shared per cone; the
    // inner loop vectorizes.
    const float *bx = m_corners[0].data(), *by = m_corners[1].data(), *bz = m_corners[2].data(),
                *cx = m_corners[3].data(), *cy = m_corners[4].data(), *cz = m_corners[5].data();
    const float ax = cone.apex.x - p.x, ay = cone.apex.y - p.y, az = cone.apex.z - p.z;
    const float la = std::sqrt(ax * ax + ay * ay + az * az);
    float part = 0;
#pragma omp simd reduction(+ : part)
    for (size_t t = cone.first; t < cone.first + cone.count; ++t) {
        float ux = bx[t] - p.x, uy = by[t] - p.y, uz = bz[t] - p.z;
        float vx = cx[t] - p.x, vy = cy[t] - p.y, vz = cz[t] - p.z;
        float lb = std::sqrt(ux * ux + uy * uy + uz * uz);
        float lc = std::sqrt(vx * vx + vy * vy + vz * vz);
        float num = ax * (uy * vz - uz * vy) + ay * (uz * vx - ux * vz) + az * (ux * vy - uy * vx);
        float den = la * lb * lc + (ax * ux + ay * uy + az * uz) * lc +
                    (ax * vx + ay * vy + az * vz) * lb + (ux * vx + uy * vy + uz * vz) * la;
        part += fastAtan2(num, den);
    }
    return part;
}

double ClosingFilm::gradientBound(Vec3 lo, Vec3 hi) const {
    if (m_groups.empty()) return 0;
    // Distances from the box are at least those from its centre less its half diagonal.
    const Vec3 centre = (lo + hi) * 0.5f;
    const double half = 0.5 * length(hi - lo) * 1.0001 + 1e-30;
    double sum = 0;
    // Groups of loops far from the box are bounded together: each loop i lies in a ball of
    // radius R_i inside the group's, at least g away, so the dipole-like bounds add up to
    // 2 sum(L_i R_i) / g^3 (and the plain ones to sum(L_i) / g^2).
    int stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Group& grp = m_groups[stack[--top]];
        const double g = length(centre - grp.centre) - grp.radius - half;
        if (g > 3.0 * grp.radius) {
            sum += std::min(grp.length / (g * g), 2.0 * grp.lengthRadius / (g * g * g));
        } else if (grp.cone >= 0) {
            const double b = coneGradientBound(m_cones[grp.cone], centre, half);
            if (!std::isfinite(b)) return INFINITY;
            sum += b;
        } else {
            stack[top++] = grp.left;
            stack[top++] = grp.right;
        }
    }
    return sum / kFourPi;
}

ClosingFilm::Taylor ClosingFilm::taylor(Vec3 centre, float half) const {
    Taylor t;
    t.valid = true;
    if (m_groups.empty()) return t;
    int stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0 && t.valid) {
        const Group& grp = m_groups[stack[--top]];
        const float gap = length(centre - grp.centre) - grp.radius - half;
        if (gap > grp.radius) {
            const float bound = grp.area / (static_cast<float>(kFourPi) * gap * gap) * 1.001f;
            if (bound < 0.01f) {
                t.error += bound;
                continue;
            }
        }
        if (grp.cone >= 0) {
            t.valid = addCone(m_cones[grp.cone], centre, half, t);
        } else {
            stack[top++] = grp.left;
            stack[top++] = grp.right;
        }
    }
    t.value *= static_cast<float>(2.0 / kFourPi);
    t.gradient = t.gradient * static_cast<float>(1.0 / kFourPi);
    t.quadratic *= static_cast<float>(1.0 / kFourPi);
    // The float sums' rounding: the atan2's as in windingFast, the rest relative.
    t.error += fastError() + 1e-5f * std::fabs(t.value);
    t.quadratic *= 1.001f;
    return t;
}

// One cone's part of a Taylor model (times 4 pi, its value times 2 pi): false where the ball
// reaches its rim.
bool ClosingFilm::addCone(const Cone& cone, Vec3 centre, float half, Taylor& t) const {
    t.value += coneWinding(cone, centre);
    // The film's boundary runs against the rim (b -> a for rim edge a -> b). The solid angle's
    // gradient is the Biot-Savart integral of the boundary; a straight piece from a to b gives
    // (ra x rb)(|ra| + |rb|) / (|ra| |rb| (|ra| |rb| + ra . rb)), ra = a - p, rb = b - p.
    for (size_t e = cone.first; e < cone.first + cone.count; ++e) {
        const Vec3 ra = m_edges[e].b - centre, rb = m_edges[e].a - centre;
        const float la = length(ra), lb = length(rb);
        const float den = la * lb * (la * lb + dot(ra, rb));
        if (!(den > 0)) return false;
        t.gradient = t.gradient + cross(ra, rb) * ((la + lb) / den);
    }
    // |H| <= sum over the rim of 2 |dl| / g^3, g the distance from the ball.
    const double h = rimSum(cone, centre, half, 3);
    t.quadratic += static_cast<float>(h);  // half the Hessian's bound
    return std::isfinite(h);
}

void ClosingFilm::trianglesNear(Vec3 lo, Vec3 hi, float eps, std::vector<uint32_t>& out) const {
    out.clear();
    if (m_groups.empty()) return;
    lo = lo - Vec3(eps);
    hi = hi + Vec3(eps);
    int stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Group& grp = m_groups[stack[--top]];
        // A group's ball holds its loops' balls, and a loop's ball its cone (the apex is the mean
        // of the loop's vertices).
        const Vec3 nearest = min(max(grp.centre, lo), hi);
        if (length(grp.centre - nearest) > grp.radius) continue;
        if (grp.cone < 0) {
            stack[top++] = grp.left;
            stack[top++] = grp.right;
            continue;
        }
        const Cone& cone = m_cones[grp.cone];
        for (size_t t = cone.first; t < cone.first + cone.count; ++t) {
            const CrossingTriangle& f = m_films[t];
            if (f.lo.x <= hi.x && f.lo.y <= hi.y && f.lo.z <= hi.z && f.hi.x >= lo.x &&
                f.hi.y >= lo.y && f.hi.z >= lo.z)
                out.push_back(static_cast<uint32_t>(t));
        }
    }
}

// One loop's part of the bound (times 4 pi) over the ball of radius `half` about `centre`.
double ClosingFilm::coneGradientBound(const Cone& cone, Vec3 centre, double half) const {
    // A far loop: the dipole-like bound (or the plain one where that is smaller).
    const Node& root = m_nodes[cone.root];
    const double g = length(centre - root.centre) - root.radius - half;
    if (g > root.radius)
        return std::min(root.length / (g * g), 2.0 * root.length * root.radius / (g * g * g));
    return rimSum(cone, centre, half, 2);
}

// The sum over a loop's edges of |dl| / g^power, g the distance from the ball of radius `half`
// about `centre` (+infinity where the ball reaches the rim), by its edges' tree (balanced, so 64
// levels are far more than enough).
double ClosingFilm::rimSum(const Cone& cone, Vec3 centre, double half, int power) const {
    auto inverse = [power](double g) { return power == 2 ? 1 / (g * g) : 1 / (g * g * g); };
    double sum = 0;
    int stack[64];
    int top = 0;
    stack[top++] = cone.root;
    while (top > 0) {
        const Node& n = m_nodes[stack[--top]];
        const double gn = length(centre - n.centre) - n.radius - half;
        if (gn > 4.0 * n.radius) {
            sum += n.length * inverse(gn);  // far: all its length at the ball's distance
        } else if (n.left < 0) {
            for (int e = n.first; e < n.first + n.count; ++e) {
                const double ge =
                    pointSegmentDistance(centre, m_edges[e].a, m_edges[e].b) * 0.9999 - half;
                if (ge <= 0) return INFINITY;
                sum += 1.0001 * length(m_edges[e].b - m_edges[e].a) * inverse(ge);
            }
        } else {
            stack[top++] = n.left;
            stack[top++] = n.right;
        }
    }
    return sum;
}

}  // namespace sdft
