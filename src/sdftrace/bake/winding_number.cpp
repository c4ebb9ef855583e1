#include "sdftrace/bake/winding_number.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "sdftrace/math/vec3d.h"

namespace sdft {

namespace {
constexpr double kFourPi = 12.566370614359172;
constexpr int kLeafSize = 8;
constexpr int kParallelBuild = 16384;  // triangles below which a subtree builds in one task

}  // namespace

// Van Oosterom & Strackee 1983: tan(Omega / 2) = a.(b x c) / (|a||b||c| + (a.b)|c| + (a.c)|b| +
// (b.c)|a|) with a, b, c the vertices relative to p.
double triangleSolidAngle(Vec3 p, Vec3 va, Vec3 vb, Vec3 vc) {
    Vec3d a = difference(va, p), b = difference(vb, p), c = difference(vc, p);
    double la = norm(a), lb = norm(b), lc = norm(c);
    double num = dot(a, cross(b, c));
    double den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    return 2.0 * std::atan2(num, den);
}

namespace {

// The solid angle of Van Oosterom & Strackee in float, for the hierarchical sum's leaves.
inline float solidAngleFloat(Vec3 p, const float* t) {
    Vec3 a(t[0] - p.x, t[1] - p.y, t[2] - p.z), b(t[3] - p.x, t[4] - p.y, t[5] - p.z),
        c(t[6] - p.x, t[7] - p.y, t[8] - p.z);
    float la = length(a), lb = length(b), lc = length(c);
    float num = dot(a, cross(b, c));
    float den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    return 2.0f * fastAtan2(num, den);
}

}  // namespace

WindingNumber::WindingNumber(const TriangleMesh& mesh, double beta) : m_mesh(mesh), m_beta(beta) {
    m_order.resize(mesh.triangles.size());
    std::iota(m_order.begin(), m_order.end(), 0);
    if (!mesh.triangles.empty()) {
        // The tree's shape follows from the triangle count alone (median splits), so each
        // subtree's nodes have known indices (depth first, left before right) and the two halves
        // of a node build in parallel into the same array as a sequential build would.
        const int n = static_cast<int>(mesh.triangles.size());
        std::map<int, int> sizes;
        subtreeSize(n, sizes);
        m_nodes.resize(sizes.at(n));
        build(0, n, 0, sizes);
    }
    // Leaves read their triangles' corners from one contiguous array, in tree order.
    m_corners.reserve(9 * m_order.size());
    for (int t : m_order)
        for (uint32_t v : mesh.triangles[t]) {
            Vec3 q = mesh.positions[v];
            m_corners.insert(m_corners.end(), {q.x, q.y, q.z});
        }
}

int WindingNumber::subtreeSize(int count, std::map<int, int>& sizes) {
    if (auto it = sizes.find(count); it != sizes.end()) return it->second;
    int nodes = 1;
    if (count > kLeafSize)
        nodes += subtreeSize(count / 2, sizes) + subtreeSize(count - count / 2, sizes);
    sizes[count] = nodes;
    return nodes;
}

void WindingNumber::build(int first, int count, int index, const std::map<int, int>& sizes) {
    Node n;
    n.first = first;
    n.count = count;
    Bounds3 b, centroids;
    double area = 0, cx = 0, cy = 0, cz = 0, nx = 0, ny = 0, nz = 0;
    for (int i = first; i < first + count; ++i) {
        const auto& t = m_mesh.triangles[m_order[i]];
        Vec3 p0 = m_mesh.positions[t[0]], p1 = m_mesh.positions[t[1]], p2 = m_mesh.positions[t[2]];
        for (Vec3 v : {p0, p1, p2}) b.include(v);
        Vec3 c = (p0 + p1 + p2) / 3.0f;
        centroids.include(c);
        Vec3d cr = cross(difference(p1, p0), difference(p2, p0));  // 2 * area * unit normal
        double a = 0.5 * norm(cr);
        area += a;
        cx += a * c.x, cy += a * c.y, cz += a * c.z;
        nx += 0.5 * cr.x, ny += 0.5 * cr.y, nz += 0.5 * cr.z;
    }
    if (area > 0) cx /= area, cy /= area, cz /= area;
    n.lo = b.lo;
    n.hi = b.hi;
    n.cx = cx, n.cy = cy, n.cz = cz;
    n.nx = nx, n.ny = ny, n.nz = nz;
    // One square root for the largest squared distance: the root is monotone, so this is the
    // largest of the roots exactly.
    double radius2 = 0;
    for (int i = first; i < first + count; ++i)
        for (uint32_t v : m_mesh.triangles[m_order[i]]) {
            Vec3 p = m_mesh.positions[v];
            radius2 = std::max(radius2, (p.x - cx) * (p.x - cx) + (p.y - cy) * (p.y - cy) +
                                            (p.z - cz) * (p.z - cz));
        }
    n.radius = std::sqrt(radius2);
    if (count > kLeafSize) {
        // Median split of the centroids along the longest axis.
        Vec3 e = centroids.extent();
        int axis = e.x > e.y ? (e.x > e.z ? 0 : 2) : (e.y > e.z ? 1 : 2);
        int mid = first + count / 2;
        auto key = [&](int t) {
            const auto& tri = m_mesh.triangles[t];
            return m_mesh.positions[tri[0]][axis] + m_mesh.positions[tri[1]][axis] +
                   m_mesh.positions[tri[2]][axis];
        };
        std::nth_element(m_order.begin() + first, m_order.begin() + mid,
                         m_order.begin() + first + count,
                         [&](int a, int c) { return key(a) < key(c); });
        n.left = index + 1;
        n.right = index + 1 + sizes.at(mid - first);
        auto left = [&] { build(first, mid - first, n.left, sizes); };
        auto right = [&] { build(mid, first + count - mid, n.right, sizes); };
        if (count > kParallelBuild)
            tbb::parallel_invoke(left, right);
        else
            left(), right();
    }
    m_nodes[index] = n;
}

double WindingNumber::exact(Vec3 p) const {
    double sum = 0;
    for (const auto& t : m_mesh.triangles)
        sum += triangleSolidAngle(p, m_mesh.positions[t[0]], m_mesh.positions[t[1]],
                                  m_mesh.positions[t[2]]);
    return sum / kFourPi;
}

bool WindingNumber::inside(Vec3 p) const {
    double coarse = fast(p, 1.5);
    if (std::fabs(coarse - 0.5) > 0.3) return coarse > 0.5;
    return fast(p) > 0.5;
}

double WindingNumber::fast(Vec3 p, double beta) const {
    if (m_nodes.empty()) return 0;
    double sum = 0;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& n = m_nodes[stack[--top]];
        double dx = n.cx - p.x, dy = n.cy - p.y, dz = n.cz - p.z;
        double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 > beta * beta * n.radius * n.radius) {
            // Far: the dipole term, Omega ~ (c - p).N / |c - p|^3 (Barill et al. 2018, eq. 8).
            sum += (dx * n.nx + dy * n.ny + dz * n.nz) / (d2 * std::sqrt(d2));
        } else if (n.left < 0) {
            float leaf = 0;
            for (int i = n.first; i < n.first + n.count; ++i)
                leaf += solidAngleFloat(p, m_corners.data() + 9 * static_cast<size_t>(i));
            sum += leaf;
        } else {
            stack[top++] = n.left;
            stack[top++] = n.right;
        }
    }
    return sum / kFourPi;
}

}  // namespace sdft
