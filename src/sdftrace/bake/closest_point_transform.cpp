#include "sdftrace/bake/closest_point_transform.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <memory>
#include <vector>

#include "sdftrace/bake/closest_point.h"
#include "sdftrace/exec/progress.h"
#include "sdftrace/math/vec3d.h"

namespace sdft {
namespace {

// Regions are grown by this (voxels): far above the rounding of the float row clipping (about
// 1e-4 at 1024 voxels), so the true closest feature is always among those evaluated.
constexpr double kGrow = 1e-3;

struct Plane {
    Vec3d n;
    double c;  // n . x <= c
};

// A convex polytope as its faces' vertex loops, of fixed capacity: a cut that would overflow it
// is skipped, which only grows the region (still correct, a little more work).
constexpr int kMaxLoop = 40, kMaxFaces = 36;
struct Loop {
    int n = 0;
    Vec3d v[kMaxLoop];
};
struct Polytope {
    int faces = 0;
    Loop f[kMaxFaces];
};

void makeBox(Polytope& p, Vec3d lo, Vec3d hi) {
    auto corner = [&](int i) {
        return Vec3d{(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z};
    };
    static constexpr int kQuads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                         {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
    p.faces = 6;
    for (int f = 0; f < 6; ++f) {
        p.f[f].n = 4;
        for (int k = 0; k < 4; ++k) p.f[f].v[k] = corner(kQuads[f][k]);
    }
}

enum class Cut { Unchanged, Empty, Clipped };

// `p` cut to h.n . x <= h.c, into `out` (Sutherland-Hodgman on every face, the cut points
// ordered around their centroid closing the hole).
Cut clip(const Polytope& p, const Plane& h, Polytope& out) {
    double lo = INFINITY, hi = -INFINITY;
    for (int f = 0; f < p.faces; ++f) {
        for (int i = 0; i < p.f[f].n; ++i) {
            const double d = dot(h.n, p.f[f].v[i]) - h.c;
            lo = std::min(lo, d);
            hi = std::max(hi, d);
        }
    }
    if (hi <= 0) return Cut::Unchanged;
    if (lo > 0) return Cut::Empty;
    Vec3d cuts[2 * kMaxFaces];
    int nc = 0;
    out.faces = 0;
    for (int f = 0; f < p.faces; ++f) {
        const Loop& in = p.f[f];
        Loop& o = out.f[out.faces];
        o.n = 0;
        for (int i = 0; i < in.n; ++i) {
            const Vec3d& a = in.v[i];
            const Vec3d& b = in.v[(i + 1) % in.n];
            const double da = dot(h.n, a) - h.c, db = dot(h.n, b) - h.c;
            if (da <= 0) {
                if (o.n == kMaxLoop) return Cut::Unchanged;
                o.v[o.n++] = a;
            }
            if ((da <= 0) != (db <= 0)) {
                if (o.n == kMaxLoop || nc == 2 * kMaxFaces) return Cut::Unchanged;
                const Vec3d x = a + (b - a) * (da / (da - db));
                o.v[o.n++] = x;
                cuts[nc++] = x;
            }
        }
        if (o.n >= 3) ++out.faces;
    }
    if (nc >= 3) {
        if (out.faces == kMaxFaces) return Cut::Unchanged;
        Vec3d g;
        for (int i = 0; i < nc; ++i) g = g + cuts[i];
        g = g * (1.0 / nc);
        const Vec3d n = h.n * (1.0 / norm(h.n));
        Vec3d u = cross(n, std::fabs(n.x) < 0.6 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0});
        u = u * (1.0 / norm(u));
        const Vec3d w = cross(n, u);
        std::array<std::pair<double, int>, 2 * kMaxFaces> order;
        for (int i = 0; i < nc; ++i)
            order[i] = {std::atan2(dot(cuts[i] - g, w), dot(cuts[i] - g, u)), i};
        std::sort(order.begin(), order.begin() + nc);
        Loop& cap = out.f[out.faces];
        cap.n = 0;
        for (int i = 0; i < nc && cap.n < kMaxLoop; ++i) {
            const Vec3d& x = cuts[order[i].second];
            if (cap.n > 0 && norm(x - cap.v[cap.n - 1]) < 1e-12) continue;
            cap.v[cap.n++] = x;
        }
        if (cap.n >= 3) ++out.faces;
    }
    return out.faces ? Cut::Clipped : Cut::Empty;
}

struct P2 {
    float b, c;
};

// Convex hull (Andrew's monotone chain), counter-clockwise; returns its doubled area.
double hull(std::vector<P2>& pts, std::vector<P2>& out) {
    std::sort(pts.begin(), pts.end(),
              [](const P2& p, const P2& q) { return p.b < q.b || (p.b == q.b && p.c < q.c); });
    out.assign(2 * pts.size() + 1, P2{});
    auto turn = [](const P2& o, const P2& a, const P2& b) {
        return (double(a.b) - o.b) * (double(b.c) - o.c) -
               (double(a.c) - o.c) * (double(b.b) - o.b);
    };
    size_t k = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
        while (k >= 2 && turn(out[k - 2], out[k - 1], pts[i]) <= 0) --k;
        out[k++] = pts[i];
    }
    for (size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
        while (k >= t && turn(out[k - 2], out[k - 1], pts[i]) <= 0) --k;
        out[k++] = pts[i];
    }
    out.resize(k > 1 ? k - 1 : k);
    double area = 0;
    for (size_t i = 0; i < out.size(); ++i) {
        const P2& p = out[i];
        const P2& q = out[(i + 1) % out.size()];
        area += double(p.b) * q.c - double(q.b) * p.c;
    }
    return std::fabs(area);
}

enum class Kind : uint8_t { Face, Edge, Vertex };

// Rows run along `axis`; the scan's outer loop runs along z, or along y for rows along z, so that
// slabs of layers across the outer axis own disjoint samples.
inline int outerAxis(int axis) { return axis == 2 ? 1 : 2; }
inline int innerAxis(int axis) { return 3 - axis - outerAxis(axis); }

// A feature's region cut to the grid: its row axis, the projection of its polytope along that
// axis (inner, outer coordinates: the rows to visit), its integer bounds and its half-spaces
// (each row's run).
struct Scan {
    Kind kind;
    uint8_t axis = 0;
    uint32_t id = 0;
    int lo[3], hi[3];
    std::vector<P2> hull;
    std::vector<std::array<float, 4>> planes;
};

struct Scratch {
    std::unique_ptr<Polytope> a = std::make_unique<Polytope>(), b = std::make_unique<Polytope>();
    std::vector<P2> pts, hull;
};

class Transform {
  public:
    Transform(const TriangleMesh& mesh, const GridShape& shape) : m_mesh(mesh), m_shape(shape) {
        const size_t nv = mesh.positions.size();
        m_pd.resize(nv);
        m_pf.resize(nv);
        for (size_t v = 0; v < nv; ++v) {
            const Vec3 q = (mesh.positions[v] - shape.origin) / shape.voxelSize;
            m_pd[v] = {q.x, q.y, q.z};
            m_pf[v] = q;
        }
        // Unique undirected edges, with the faces holding each.
        std::vector<std::pair<uint64_t, uint32_t>> keys;
        keys.reserve(mesh.triangles.size() * 3);
        for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
            for (int k = 0; k < 3; ++k) {
                uint32_t u = mesh.triangles[t][k], w = mesh.triangles[t][(k + 1) % 3];
                if (u > w) std::swap(u, w);
                keys.push_back({(uint64_t(u) << 32) | w, t});
            }
        }
        std::sort(keys.begin(), keys.end());
        for (size_t i = 0; i < keys.size();) {
            size_t j = i;
            while (j < keys.size() && keys[j].first == keys[i].first) ++j;
            m_edges.push_back({uint32_t(keys[i].first >> 32), uint32_t(keys[i].first)});
            m_edgeFaces.push_back(static_cast<uint32_t>(m_faceList.size()));
            for (size_t k = i; k < j; ++k) m_faceList.push_back(keys[k].second);
            i = j;
        }
        m_edgeFaces.push_back(static_cast<uint32_t>(m_faceList.size()));
        // Each vertex's neighbours along the unique edges.
        m_vertexEdges.assign(nv + 1, 0);
        for (const auto& e : m_edges) {
            ++m_vertexEdges[e[0] + 1];
            ++m_vertexEdges[e[1] + 1];
        }
        for (size_t v = 0; v < nv; ++v) m_vertexEdges[v + 1] += m_vertexEdges[v];
        m_neighbours.resize(m_vertexEdges[nv]);
        std::vector<uint32_t> fill(m_vertexEdges.begin(), m_vertexEdges.end() - 1);
        for (const auto& e : m_edges) {
            m_neighbours[fill[e[0]]++] = e[1];
            m_neighbours[fill[e[1]]++] = e[0];
        }
        m_limit = distanceBound();
    }

    double limit() const { return m_limit; }
    size_t features() const {
        return m_mesh.triangles.size() + m_edges.size() + m_mesh.positions.size();
    }

    // Feature f: faces first, then edges, then vertices. False when its region misses the grid.
    bool build(size_t f, Scratch& s, Scan& out) const {
        std::vector<Plane> planes;
        Vec3d lo, hi;
        const size_t nt = m_mesh.triangles.size(), ne = m_edges.size();
        bool ok;
        if (f < nt) {
            ok = facePrism(static_cast<uint32_t>(f), planes, lo, hi, out);
        } else if (f < nt + ne) {
            ok = edgeWedge(static_cast<uint32_t>(f - nt), planes, lo, hi, out);
        } else {
            ok = vertexCone(static_cast<uint32_t>(f - nt - ne), planes, lo, hi, out);
        }
        return ok && cutToGrid(planes, lo, hi, s, out);
    }

    // Scan-converts `s` within layers o0..o1 (inclusive) of its outer axis, keeping squared
    // distances in `d2`.
    void rasterize(const Scan& s, int o0, int o1, float* d2, size_t& rows,
                   size_t& evaluations) const {
        constexpr float g = static_cast<float>(kGrow);
        if (s.kind == Kind::Face) {
            // Inside the prism proper: the plane distance; otherwise (the grown rim) the
            // triangle's.
            const auto& t = m_mesh.triangles[s.id];
            const Vec3 fa = m_pf[t[0]], fb = m_pf[t[1]], fc = m_pf[t[2]];
            const Vec3 fn = normalize(cross(fb - fa, fc - fa));
            const float foff = dot(fn, fa);
            scan(s, o0, o1, d2, rows, evaluations, [&](Vec3 q) {
                bool inside = true;
                for (int k = 0; k < 3; ++k) {
                    const auto& h = s.planes[k];
                    inside &= h[0] * q.x + h[1] * q.y + h[2] * q.z <= h[3] - 2 * g;
                }
                if (inside) {
                    const float d = dot(fn, q) - foff;
                    return d * d;
                }
                const Vec3 r = q - closestPointOnTriangle(q, fa, fb, fc);
                return dot(r, r);
            });
        } else if (s.kind == Kind::Edge) {
            const Vec3 fa = m_pf[m_edges[s.id][0]], fb = m_pf[m_edges[s.id][1]];
            const float flen = length(fb - fa);
            const Vec3 fn = (fb - fa) / flen;
            scan(s, o0, o1, d2, rows, evaluations, [&](Vec3 q) {
                const float t = std::clamp(dot(q - fa, fn), 0.0f, flen);
                const Vec3 r = q - (fa + fn * t);
                return dot(r, r);
            });
        } else {
            const Vec3 fa = m_pf[s.id];
            scan(s, o0, o1, d2, rows, evaluations, [&](Vec3 q) {
                const Vec3 r = q - fa;
                return dot(r, r);
            });
        }
    }

  private:
    // A face's prism: the planes through its edges perpendicular to it (grown by kGrow).
    bool facePrism(uint32_t id, std::vector<Plane>& planes, Vec3d& lo, Vec3d& hi, Scan& out) const {
        out.kind = Kind::Face;
        out.id = id;
        const auto& t = m_mesh.triangles[id];
        const Vec3d a = m_pd[t[0]], b = m_pd[t[1]], c = m_pd[t[2]];
        Vec3d n = cross(b - a, c - a);
        const double longest = std::max({dot(b - a, b - a), dot(c - b, c - b), dot(a - c, a - c)});
        // A sliver this thin is within 1e-10 of its edges, which stand for it.
        if (dot(n, n) <= 1e-20 * longest * longest) return false;
        n = n * (1.0 / norm(n));
        const Vec3d v[3] = {a, b, c};
        for (int k = 0; k < 3; ++k) {
            Vec3d m = cross(v[(k + 1) % 3] - v[k], n);
            m = m * (1.0 / norm(m));
            planes.push_back({m, dot(m, v[k]) + kGrow});
        }
        lo = {std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})};
        hi = {std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})};
        return true;
    }

    // An edge's wedge: between the planes through its ends perpendicular to it, and outside each
    // adjacent face's plane through the edge.
    bool edgeWedge(uint32_t id, std::vector<Plane>& planes, Vec3d& lo, Vec3d& hi, Scan& out) const {
        out.kind = Kind::Edge;
        out.id = id;
        const auto& e = m_edges[id];
        const Vec3d a = m_pd[e[0]], b = m_pd[e[1]];
        const double len = norm(b - a);
        if (len == 0) return false;
        const Vec3d u = (b - a) * (1.0 / len);
        planes.push_back({u * -1.0, -dot(u, a) + kGrow});
        planes.push_back({u, dot(u, b) + kGrow});
        for (uint32_t k = m_edgeFaces[id]; k < m_edgeFaces[id + 1]; ++k) {
            const auto& t = m_mesh.triangles[m_faceList[k]];
            const uint32_t w = t[0] != e[0] && t[0] != e[1]   ? t[0]
                               : t[1] != e[0] && t[1] != e[1] ? t[1]
                                                              : t[2];
            Vec3d m = a - m_pd[w];
            m = m - u * dot(m, u);
            const double ml = norm(m);
            if (ml <= 1e-12 * len) continue;  // a sliver: no constraint (a larger region)
            m = m * (1.0 / ml);
            planes.push_back({m * -1.0, -dot(m, a) + kGrow});
        }
        lo = {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
        hi = {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
        return true;
    }

    // A vertex's cone: behind the plane perpendicular to each edge leaving it.
    bool vertexCone(uint32_t id, std::vector<Plane>& planes, Vec3d& lo, Vec3d& hi,
                    Scan& out) const {
        out.kind = Kind::Vertex;
        out.id = id;
        if (m_vertexEdges[id] == m_vertexEdges[id + 1]) return false;  // unused
        const Vec3d v = m_pd[id];
        for (uint32_t k = m_vertexEdges[id]; k < m_vertexEdges[id + 1]; ++k) {
            Vec3d u = m_pd[m_neighbours[k]] - v;
            const double ul = norm(u);
            if (ul == 0) continue;
            u = u * (1.0 / ul);
            planes.push_back({u, dot(u, v) + kGrow});
        }
        lo = hi = v;
        return true;
    }

    // The region `planes` cut from the feature's box grown by the distance limit and clipped to
    // the grid: its vertex range, the scan axis with the smallest projected hull, and the planes.
    bool cutToGrid(const std::vector<Plane>& planes, Vec3d lo, Vec3d hi, Scratch& s,
                   Scan& out) const {
        // Within the grid and within the largest distance of any vertex.
        double l3[3] = {lo.x, lo.y, lo.z}, h3[3] = {hi.x, hi.y, hi.z};
        for (int k = 0; k < 3; ++k) {
            l3[k] = std::max(l3[k] - m_limit, 0.0);
            h3[k] = std::min(h3[k] + m_limit, double(m_shape.cells[k]));
            if (l3[k] > h3[k]) return false;
        }
        Polytope* cur = s.a.get();
        Polytope* next = s.b.get();
        makeBox(*cur, {l3[0], l3[1], l3[2]}, {h3[0], h3[1], h3[2]});
        for (const Plane& h : planes) {
            const Cut c = clip(*cur, h, *next);
            if (c == Cut::Empty) return false;
            if (c == Cut::Clipped) std::swap(cur, next);
        }
        double mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int i = 0; i < cur->faces; ++i) {
            for (int j = 0; j < cur->f[i].n; ++j) {
                for (int k = 0; k < 3; ++k) {
                    mn[k] = std::min(mn[k], cur->f[i].v[j][k]);
                    mx[k] = std::max(mx[k], cur->f[i].v[j][k]);
                }
            }
        }
        for (int k = 0; k < 3; ++k) {
            out.lo[k] = std::max(0, static_cast<int>(std::ceil(mn[k] - kGrow)));
            out.hi[k] = std::min(m_shape.cells[k], static_cast<int>(std::floor(mx[k] + kGrow)));
            if (out.lo[k] > out.hi[k]) return false;
        }
        // Rows along the axis whose projection is smallest: the fewest rows.
        double best = INFINITY;
        for (int a = 0; a < 3; ++a) {
            const int b = innerAxis(a), c = outerAxis(a);
            s.pts.clear();
            for (int i = 0; i < cur->faces; ++i)
                for (int j = 0; j < cur->f[i].n; ++j)
                    s.pts.push_back({float(cur->f[i].v[j][b]), float(cur->f[i].v[j][c])});
            const double area = hull(s.pts, s.hull);
            if (area < best) {
                best = area;
                out.axis = static_cast<uint8_t>(a);
                out.hull = s.hull;
            }
        }
        out.planes.clear();
        for (const Plane& h : planes)
            out.planes.push_back({float(h.n.x), float(h.n.y), float(h.n.z), float(h.c)});
        return true;
    }

    // The hull's extent along the inner axis within outer layer ic +- kGrow; false if none.
    static bool hullExtent(const Scan& s, int ic, float& bmin, float& bmax) {
        constexpr float g = static_cast<float>(kGrow);
        const size_t nh = s.hull.size();
        bmin = INFINITY;
        bmax = -INFINITY;
        for (size_t i = 0; i < nh; ++i) {
            const P2& p = s.hull[i];
            const P2& q = s.hull[(i + 1) % nh];
            if (std::max(p.c, q.c) < ic - g || std::min(p.c, q.c) > ic + g) continue;
            float t0 = 0, t1 = 1;
            const float dc = q.c - p.c;
            if (std::fabs(dc) > 1e-9f) {
                float ta = (ic - g - p.c) / dc, tb = (ic + g - p.c) / dc;
                if (ta > tb) std::swap(ta, tb);
                t0 = std::max(0.0f, ta);
                t1 = std::min(1.0f, tb);
                if (t0 > t1) continue;
            }
            const float b0 = p.b + (q.b - p.b) * t0, b1 = p.b + (q.b - p.b) * t1;
            bmin = std::min(bmin, std::min(b0, b1));
            bmax = std::max(bmax, std::max(b0, b1));
        }
        return bmin <= bmax;
    }

    // The scan axis's range [alo, ahi] of row (ib, ic) inside the region's planes.
    static bool rowRange(const Scan& s, int ib, int ic, float& alo, float& ahi) {
        const int a = s.axis, b = innerAxis(a), c = outerAxis(a);
        for (const auto& h : s.planes) {
            const float rhs = h[3] - h[b] * ib - h[c] * ic;
            if (h[a] > 1e-7f) {
                ahi = std::min(ahi, rhs / h[a]);
            } else if (h[a] < -1e-7f) {
                alo = std::max(alo, rhs / h[a]);
            } else if (rhs < -1e-4f) {
                return false;
            }
        }
        return alo <= ahi;
    }

    // Every vertex of the region within layers o0..o1: d2 = min(d2, distance2(vertex)).
    template <class Distance2>
    void scan(const Scan& s, int o0, int o1, float* d2, size_t& rows, size_t& evaluations,
              Distance2&& distance2) const {
        constexpr float g = static_cast<float>(kGrow);
        const int a = s.axis, b = innerAxis(a), c = outerAxis(a);
        int lo[3] = {s.lo[0], s.lo[1], s.lo[2]};
        int hi[3] = {s.hi[0], s.hi[1], s.hi[2]};
        lo[c] = std::max(lo[c], o0);
        hi[c] = std::min(hi[c], o1);
        if (lo[c] > hi[c]) return;
        const size_t stride[3] = {1, size_t(m_shape.vertices(0)),
                                  size_t(m_shape.vertices(0)) * m_shape.vertices(1)};
        for (int ic = lo[c]; ic <= hi[c]; ++ic) {
            float bmin, bmax;
            if (!hullExtent(s, ic, bmin, bmax)) continue;
            const int ib0 = std::max(lo[b], static_cast<int>(std::ceil(bmin - g)));
            const int ib1 = std::min(hi[b], static_cast<int>(std::floor(bmax + g)));
            for (int ib = ib0; ib <= ib1; ++ib) {
                float alo = static_cast<float>(lo[a]), ahi = static_cast<float>(hi[a]);
                if (!rowRange(s, ib, ic, alo, ahi)) continue;
                const int ia0 = static_cast<int>(std::ceil(alo)),
                          ia1 = static_cast<int>(std::floor(ahi));
                if (ia0 > ia1) continue;
                ++rows;
                evaluations += static_cast<size_t>(ia1 - ia0 + 1);
                float p[3];
                p[b] = static_cast<float>(ib);
                p[c] = static_cast<float>(ic);
                float* row = d2 + stride[b] * ib + stride[c] * ic;
                const size_t sa = stride[a];
                for (int ia = ia0; ia <= ia1; ++ia) {
                    p[a] = static_cast<float>(ia);
                    float& o = row[sa * ia];
                    o = std::min(o, distance2(Vec3(p[0], p[1], p[2])));
                }
            }
        }
    }

    // The largest distance (voxels) any grid vertex can have: from a lattice of every s-th
    // vertex, the distance to the nearest of (up to 1024) mesh vertices bounds the distance to
    // the mesh; a vertex is within s*sqrt(3)/2 of a lattice point.
    double distanceBound() const {
        const size_t nv = m_pd.size();
        const size_t stride = std::max<size_t>(1, nv / 1024);
        int step = 1;
        for (int k = 0; k < 3; ++k) step = std::max(step, m_shape.cells[k] / 16);
        std::vector<int> at[3];
        for (int k = 0; k < 3; ++k) {
            for (int i = 0; i < m_shape.cells[k]; i += step) at[k].push_back(i);
            at[k].push_back(m_shape.cells[k]);
        }
        double worst = 0;
        for (int z : at[2]) {
            for (int y : at[1]) {
                for (int x : at[0]) {
                    const Vec3d p{double(x), double(y), double(z)};
                    double best = INFINITY;
                    for (size_t v = 0; v < nv; v += stride) {
                        const Vec3d d = m_pd[v] - p;
                        best = std::min(best, dot(d, d));
                    }
                    worst = std::max(worst, best);
                }
            }
        }
        return std::sqrt(worst) + step * std::sqrt(3.0) / 2 + 1;
    }

    const TriangleMesh& m_mesh;
    const GridShape& m_shape;
    std::vector<Vec3d> m_pd;
    std::vector<Vec3> m_pf;
    std::vector<std::array<uint32_t, 2>> m_edges;
    std::vector<uint32_t> m_edgeFaces, m_faceList;
    std::vector<uint32_t> m_vertexEdges, m_neighbours;
    double m_limit = 0;
};

}  // namespace

void closestPointTransform(const TriangleMesh& mesh, const GridShape& shape, float* out,
                           ClosestPointTransformStats* stats, Progress* progress) {
    Transform t(mesh, shape);
    const size_t count = shape.vertexCount();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1 << 16),
                      [&](const tbb::blocked_range<size_t>& r) {
                          std::fill(out + r.begin(), out + r.end(), INFINITY);
                      });
    // Each feature's region, cut to the grid.
    std::vector<Scan> scans(t.features());
    std::vector<uint8_t> live(scans.size(), 0);
    tbb::enumerable_thread_specific<Scratch> scratch;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, scans.size(), 256),
                      [&](const tbb::blocked_range<size_t>& r) {
                          Scratch& s = scratch.local();
                          for (size_t f = r.begin(); f != r.end(); ++f)
                              live[f] = t.build(f, s, scans[f]);
                      });
    // Two passes: rows along x or y in slabs of z layers, then rows along z in slabs of y layers;
    // slabs in parallel, each owning its samples.
    std::atomic<size_t> rows{0}, evaluations{0};
    for (int pass = 0; pass < 2; ++pass) {
        const int outer = pass == 0 ? 2 : 1;
        std::vector<uint32_t> order;
        for (size_t f = 0; f < scans.size(); ++f)
            if (live[f] && outerAxis(scans[f].axis) == outer) order.push_back(uint32_t(f));
        // By first layer, so a slab stops at the first scan starting past it.
        std::sort(order.begin(), order.end(),
                  [&](uint32_t x, uint32_t y) { return scans[x].lo[outer] < scans[y].lo[outer]; });
        const int layers = shape.vertices(outer);
        constexpr int kSlab = 4;
        tbb::parallel_for(tbb::blocked_range<int>(0, (layers + kSlab - 1) / kSlab, 1),
                          [&](const tbb::blocked_range<int>& r) {
                              size_t myRows = 0, myEvaluations = 0;
                              for (int slab = r.begin(); slab != r.end(); ++slab) {
                                  const int o0 = slab * kSlab,
                                            o1 = std::min(layers - 1, o0 + kSlab - 1);
                                  for (uint32_t f : order) {
                                      const Scan& s = scans[f];
                                      if (s.lo[outer] > o1) break;
                                      if (s.hi[outer] < o0) continue;
                                      t.rasterize(s, o0, o1, out, myRows, myEvaluations);
                                  }
                                  if (progress)
                                      progress->advance(static_cast<uint64_t>(o1 - o0 + 1));
                              }
                              rows += myRows;
                              evaluations += myEvaluations;
                          });
    }
    std::vector<uint32_t> order;
    for (size_t f = 0; f < scans.size(); ++f)
        if (live[f]) order.push_back(static_cast<uint32_t>(f));
    const float h = shape.voxelSize;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1 << 16),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              out[i] = std::sqrt(out[i]) * h;
                      });
    if (stats) {
        *stats = {};
        for (uint32_t f : order) {
            const Kind k = scans[f].kind;
            ++(k == Kind::Face ? stats->faces : k == Kind::Edge ? stats->edges : stats->vertices);
        }
        stats->rows = rows.load();
        stats->evaluations = evaluations.load();
        stats->maxDistance = static_cast<float>(t.limit() * h);
    }
}

}  // namespace sdft
