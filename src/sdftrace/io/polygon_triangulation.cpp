#include "polygon_triangulation.h"

#include <cmath>

namespace sdft {

namespace {

void fan(std::span<const uint32_t> poly, std::vector<std::array<uint32_t, 3>>& out) {
    for (size_t j = 2; j < poly.size(); ++j) out.push_back({poly[0], poly[j - 1], poly[j]});
}

struct P2 {
    double x, y;
};

double cross(P2 o, P2 a, P2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

// p inside or on triangle (a, b, c) of positive orientation.
bool inTriangle(P2 p, P2 a, P2 b, P2 c) {
    return cross(a, b, p) >= 0 && cross(b, c, p) >= 0 && cross(c, a, p) >= 0;
}

}  // namespace

void triangulatePolygon(const std::vector<Vec3>& positions, std::span<const uint32_t> poly,
                        std::vector<std::array<uint32_t, 3>>& out) {
    const size_t n = poly.size();
    if (n < 4) return fan(poly, out);
    for (uint32_t i : poly)
        if (i >= positions.size()) return fan(poly, out);
    // Newell's normal; the polygon projected on the plane of its two other axes, turned so that
    // its winding is counter-clockwise there.
    double normal[3] = {0, 0, 0};
    for (size_t j = 0; j < n; ++j) {
        const Vec3& a = positions[poly[j]];
        const Vec3& b = positions[poly[(j + 1) % n]];
        normal[0] += (static_cast<double>(a.y) - b.y) * (static_cast<double>(a.z) + b.z);
        normal[1] += (static_cast<double>(a.z) - b.z) * (static_cast<double>(a.x) + b.x);
        normal[2] += (static_cast<double>(a.x) - b.x) * (static_cast<double>(a.y) + b.y);
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (std::fabs(normal[a]) > std::fabs(normal[axis])) axis = a;
    if (!(std::fabs(normal[axis]) > 0) || !std::isfinite(normal[axis])) return fan(poly, out);
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double flip = normal[axis] > 0 ? 1.0 : -1.0;
    std::vector<P2> p(n);
    for (size_t j = 0; j < n; ++j) {
        const Vec3& q = positions[poly[j]];
        p[j] = {q[u], flip * q[v]};
    }
    bool convex = true;
    for (size_t j = 0; j < n && convex; ++j)
        convex = cross(p[(j + n - 1) % n], p[j], p[(j + 1) % n]) >= 0;
    if (convex || n > kMaxEarClippedCorners) return fan(poly, out);
    // Ear clipping (Meisters): cut a corner whose triangle is convex and holds no other corner.
    std::vector<size_t> left(n);
    for (size_t j = 0; j < n; ++j) left[j] = j;
    while (left.size() > 3) {
        const size_t m = left.size();
        bool cut = false;
        for (size_t j = 0; j < m && !cut; ++j) {
            const size_t a = left[(j + m - 1) % m], b = left[j], c = left[(j + 1) % m];
            if (!(cross(p[a], p[b], p[c]) > 0)) continue;
            bool empty = true;
            for (size_t k = 0; k < m && empty; ++k) {
                const size_t o = left[k];
                if (o == a || o == b || o == c) continue;
                empty = !inTriangle(p[o], p[a], p[b], p[c]);
            }
            if (!empty) continue;
            out.push_back({poly[a], poly[b], poly[c]});
            left.erase(left.begin() + static_cast<ptrdiff_t>(j));
            cut = true;
        }
        if (!cut) break;  // self-intersecting or degenerate: the rest as a fan
    }
    std::vector<uint32_t> rest;
    for (size_t j : left) rest.push_back(poly[j]);
    fan(rest, out);
}

}  // namespace sdft
