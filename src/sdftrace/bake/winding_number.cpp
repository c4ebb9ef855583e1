#include "sdftrace/bake/winding_number.h"

#include <tbb/parallel_for.h>
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

WindingNumber::WindingNumber(const TriangleMesh& mesh, double beta) : m_mesh(mesh), m_beta(beta) {
    const size_t count = mesh.triangles.size();
    m_order.resize(count);
    if (count > 0) {
        // Per triangle the sum of its corners (3x its centroid): the splits' key, read from one
        // array instead of through the mesh's indices.
        std::vector<Vec3> sums(count);
        tbb::parallel_for(size_t(0), count, [&](size_t t) {
            const auto& tri = mesh.triangles[t];
            sums[t] = mesh.positions[tri[0]] + mesh.positions[tri[1]] + mesh.positions[tri[2]];
        });
        std::iota(m_order.begin(), m_order.end(), 0);
        // The tree's shape follows from the triangle count alone (halves of the order), so each
        // subtree's nodes have known indices (depth first, left before right) and the two halves
        // of a node build in parallel.
        const int n = static_cast<int>(count);
        std::map<int, int> sizes;
        subtreeSize(n, sizes);
        m_nodes.resize(sizes.at(n));
        build(0, n, 0, {sizes, sums});
    }
    // Leaves read their triangles' corners from one contiguous array, in tree order.
    m_corners.resize(9 * count);
    tbb::parallel_for(size_t(0), count, [&](size_t i) {
        const auto& tri = mesh.triangles[m_order[i]];
        for (int v = 0; v < 3; ++v) {
            const Vec3 q = mesh.positions[tri[v]];
            m_corners[9 * i + 3 * v] = q.x, m_corners[9 * i + 3 * v + 1] = q.y,
                                  m_corners[9 * i + 3 * v + 2] = q.z;
        }
    });
}

int WindingNumber::subtreeSize(int count, std::map<int, int>& sizes) {
    if (auto it = sizes.find(count); it != sizes.end()) return it->second;
    int nodes = 1;
    if (count > kLeafSize)
        nodes += subtreeSize(count / 2, sizes) + subtreeSize(count - count / 2, sizes);
    sizes[count] = nodes;
    return nodes;
}

// Leaves sum their triangles' moments; an inner node adds its children's (area, area-weighted
// centroid, dipole, bounds) and bounds its radius by theirs, so every triangle is read once.
void WindingNumber::build(int first, int count, int index, const BuildInput& in) {
    Node n;
    n.first = first;
    n.count = count;
    if (count > kLeafSize) {
        // Median split of the centroids along the longest axis (Barill et al. 2018).
        Bounds3 centroids;
        for (int i = first; i < first + count; ++i) centroids.include(in.sums[m_order[i]]);
        const Vec3 e = centroids.extent();
        const int axis = e.x > e.y ? (e.x > e.z ? 0 : 2) : (e.y > e.z ? 1 : 2);
        const int mid = first + count / 2;
        std::nth_element(m_order.begin() + first, m_order.begin() + mid,
                         m_order.begin() + first + count,
                         [&](int a, int c) { return in.sums[a][axis] < in.sums[c][axis]; });
        n.left = index + 1;
        n.right = index + 1 + in.sizes.at(mid - first);
        auto left = [&] { build(first, mid - first, n.left, in); };
        auto right = [&] { build(mid, first + count - mid, n.right, in); };
        if (count > kParallelBuild)
            tbb::parallel_invoke(left, right);
        else
            left(), right();
        n = windingInner(m_nodes[n.left], m_nodes[n.right], n.left, n.right);
        m_nodes[index] = n;
        return;
    }
    Bounds3 b;
    double area = 0, cx = 0, cy = 0, cz = 0, nx = 0, ny = 0, nz = 0;
    Vec3 mean(0.0f);
    for (int i = first; i < first + count; ++i) {
        const auto& t = m_mesh.triangles[m_order[i]];
        Vec3 p0 = m_mesh.positions[t[0]], p1 = m_mesh.positions[t[1]], p2 = m_mesh.positions[t[2]];
        for (Vec3 v : {p0, p1, p2}) b.include(v);
        Vec3 c = (p0 + p1 + p2) / 3.0f;
        mean += c;
        Vec3d cr = cross(difference(p1, p0), difference(p2, p0));  // 2 * area * unit normal
        double a = 0.5 * norm(cr);
        area += a;
        cx += a * c.x, cy += a * c.y, cz += a * c.z;
        nx += 0.5 * cr.x, ny += 0.5 * cr.y, nz += 0.5 * cr.z;
    }
    if (area > 0) {
        cx /= area, cy /= area, cz /= area;
    } else {
        cx = mean.x / count, cy = mean.y / count, cz = mean.z / count;  // no area: their mean
    }
    n.lo = b.lo;
    n.hi = b.hi;
    n.area = area;
    n.cx = cx, n.cy = cy, n.cz = cz;
    n.nx = nx, n.ny = ny, n.nz = nz;
    n.radius = exactRadius(first, count, cx, cy, cz);
    m_nodes[index] = n;
}

// The largest distance from (cx, cy, cz) to a vertex of triangles [first, first + count): one
// square root for the largest squared distance (the root is monotone).
double WindingNumber::exactRadius(int first, int count, double cx, double cy, double cz) const {
    double radius2 = 0;
    for (int i = first; i < first + count; ++i)
        for (uint32_t v : m_mesh.triangles[m_order[i]]) {
            Vec3 p = m_mesh.positions[v];
            radius2 = std::max(radius2, (p.x - cx) * (p.x - cx) + (p.y - cy) * (p.y - cy) +
                                            (p.z - cz) * (p.z - cz));
        }
    return std::sqrt(radius2);
}

double WindingNumber::exact(Vec3 p) const {
    double sum = 0;
    for (const auto& t : m_mesh.triangles)
        sum += triangleSolidAngle(p, m_mesh.positions[t[0]], m_mesh.positions[t[1]],
                                  m_mesh.positions[t[2]]);
    return sum / kFourPi;
}

}  // namespace sdft
