#include "sdftrace/bake/seed_signs.h"

#include <tbb/parallel_for.h>

#include "sdftrace/bake/winding_number.h"
#include "sdftrace/bake/winding_packet.h"
#include "sdftrace/core/macros.h"
#include "sdftrace/exec/thread_arena.h"
#include "sdftrace/field/vertex_loop.h"

namespace sdft {

const char* signMethodName(SignMethod m) {
    switch (m) {
        case SignMethod::WindingNumber:
            return "winding number";
        case SignMethod::RayParity:
            return "ray parity";
        case SignMethod::FloodFill:
            return "flood fill";
        case SignMethod::BetaShell:
            return "beta shell";
    }
    return "?";
}

bool parseSignMethod(const std::string& name, SignMethod& out) {
    static const std::pair<const char*, SignMethod> names[] = {
        {"winding", SignMethod::WindingNumber},
        {"parity", SignMethod::RayParity},
        {"flood", SignMethod::FloodFill},
        {"beta", SignMethod::BetaShell}};
    for (const auto& [n, m] : names) {
        if (name == n) {
            out = m;
            return true;
        }
    }
    return false;
}

std::vector<uint8_t> floodFillInside(const TriangleMesh& mesh, const GridShape& s,
                                     const SurfaceSeeds& seeds) {
    const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
    const size_t count = s.vertexCount();
    // A surface passing between two neighbours comes within h/2 of one of them, which is then a
    // seed (reach 0.87 h): 6-connected paths of non-seeds never cross it.
    std::vector<uint8_t> inside(count, 1);
    std::vector<size_t> stack;
    auto push = [&](int i, int j, int k) {
        size_t idx = (static_cast<size_t>(k) * vy + j) * vx + i;
        if (!inside[idx] || seeds.point[idx].x != kNoSeed) return;
        inside[idx] = 0;
        stack.push_back(idx);
    };
    for (int k = 0; k < vz; ++k)
        for (int j = 0; j < vy; ++j)
            for (int i = 0; i < vx; ++i)
                if (i == 0 || j == 0 || k == 0 || i == vx - 1 || j == vy - 1 || k == vz - 1)
                    push(i, j, k);
    while (!stack.empty()) {
        size_t idx = stack.back();
        stack.pop_back();
        int i = static_cast<int>(idx % vx), j = static_cast<int>((idx / vx) % vy),
            k = static_cast<int>(idx / (static_cast<size_t>(vx) * vy));
        if (i > 0) push(i - 1, j, k);
        if (i + 1 < vx) push(i + 1, j, k);
        if (j > 0) push(i, j - 1, k);
        if (j + 1 < vy) push(i, j + 1, k);
        if (k > 0) push(i, j, k - 1);
        if (k + 1 < vz) push(i, j, k + 1);
    }
    // Seeds: the side of their closest triangle's normal where the closest point is inside the
    // face. On an edge or a corner the face normal can point the wrong way (the pseudo-normal
    // problem); those few take the winding number's answer.
    std::unique_ptr<WindingNumber> winding;
    for (size_t idx = 0; idx < count; ++idx) {
        if (seeds.point[idx].x == kNoSeed) continue;
        const auto& t = mesh.triangles[seeds.triangle[idx]];
        Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
        int i = static_cast<int>(idx % vx), j = static_cast<int>((idx / vx) % vy),
            k = static_cast<int>(idx / (static_cast<size_t>(vx) * vy));
        Vec3 p = s.origin + Vec3(i, j, k) * s.voxelSize, q = seeds.point[idx];
        Vec3 n = cross(b - a, c - a);
        float area2 = dot(n, n);
        float u = dot(cross(c - b, q - b), n) / area2, v = dot(cross(a - c, q - c), n) / area2,
              w = 1 - u - v;
        if (std::fmin(u, std::fmin(v, w)) > 1e-4f) {
            inside[idx] = dot(p - q, n) < 0;
        } else {
            if (!winding) winding = std::make_unique<WindingNumber>(mesh);
            inside[idx] = winding->inside(p);
        }
    }
    return inside;
}

namespace {

// Inside by the winding number or by ray parity.
class InsideTest {
  public:
    InsideTest(const TriangleMesh& mesh, const MeshBvh* bvh, SignMethod method) : m_bvh(bvh) {
        SDFT_CHECK(method == SignMethod::WindingNumber || bvh != nullptr);
        if (method == SignMethod::WindingNumber) m_winding = std::make_unique<WindingNumber>(mesh);
    }
    bool inside(Vec3 p) const {
        return m_winding ? m_winding->inside(p) : m_bvh->insideByParity(p);
    }

  private:
    const MeshBvh* m_bvh;
    std::unique_ptr<WindingNumber> m_winding;
};

}  // namespace

void signDistances(std::vector<float>& d, const TriangleMesh& mesh, const MeshBvh* bvh,
                   const GridShape& s, const SurfaceSeeds& seeds, SignMethod method,
                   float betaVoxels, int threads) {
    SDFT_CHECK(d.size() == s.vertexCount());
    if (method == SignMethod::BetaShell) {
        const float beta = betaVoxels * s.voxelSize;
        for (float& v : d) v = std::fabs(v) - beta;
        return;
    }
    if (method == SignMethod::FloodFill) {
        std::vector<uint8_t> inside = floodFillInside(mesh, s, seeds);
        for (size_t i = 0; i < d.size(); ++i) d[i] = inside[i] ? -std::fabs(d[i]) : std::fabs(d[i]);
        return;
    }
    if (method == SignMethod::WindingNumber) {
        // Rows of vertices through the winding tree together (winding_packet.h): the same signs
        // as WindingNumber::inside per vertex.
        const WindingNumber winding(mesh);
        const WindingView w = winding.view();
        const int vx = s.vertices(0), vy = s.vertices(1), vz = s.vertices(2);
        ThreadArena arena(threads);
        arena.execute([&] {
            tbb::parallel_for(0, vz, [&](int k) {
                std::vector<Vec3> points(static_cast<size_t>(vx));
                std::vector<uint8_t> inside(static_cast<size_t>(vx));
                for (int j = 0; j < vy; ++j) {
                    for (int i = 0; i < vx; ++i)
                        points[static_cast<size_t>(i)] = s.origin + Vec3(i, j, k) * s.voxelSize;
                    windingInsideRow(w, points.data(), vx, winding.beta(), inside.data());
                    float* row = d.data() + (static_cast<size_t>(k) * vy + j) * vx;
                    for (int i = 0; i < vx; ++i)
                        row[i] =
                            inside[static_cast<size_t>(i)] ? -std::fabs(row[i]) : std::fabs(row[i]);
                }
            });
        });
        return;
    }
    InsideTest test(mesh, bvh, method);
    forEachVertex(s, threads, [&](int, int, int, size_t idx, Vec3 p) {
        d[idx] = test.inside(p) ? -std::fabs(d[idx]) : std::fabs(d[idx]);
    });
}

void signDistancesSparse(std::vector<float>& d, const TriangleMesh& mesh, const MeshBvh* bvh,
                         const GridShape& s, const SurfaceSeeds& seeds, SignMethod method,
                         float betaVoxels, int B, float bandVoxels, int threads) {
    if (method == SignMethod::BetaShell || method == SignMethod::FloodFill) {
        signDistances(d, mesh, bvh, s, seeds, method, betaVoxels, threads);
        return;
    }
    InsideTest test(mesh, bvh, method);
    const float band = bandVoxels * s.voxelSize;
    const int nb[3] = {(s.cells[0] + B - 1) / B, (s.cells[1] + B - 1) / B,
                       (s.cells[2] + B - 1) / B};
    const size_t numBlocks = static_cast<size_t>(nb[0]) * nb[1] * nb[2];
    const int vx = s.vertices(0), vy = s.vertices(1);
    auto at = [&](int i, int j, int k) {
        i = std::min(i, s.cells[0]), j = std::min(j, s.cells[1]), k = std::min(k, s.cells[2]);
        return (static_cast<size_t>(k) * vy + j) * vx + i;
    };
    // Per block: 1 = within the band (its vertices need their own sign), else 2 + inside.
    std::vector<uint8_t> state(numBlocks);
    ThreadArena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(size_t(0), numBlocks, [&](size_t b) {
            int bi = static_cast<int>(b % nb[0]), bj = static_cast<int>((b / nb[0]) % nb[1]),
                bk = static_cast<int>(b / (static_cast<size_t>(nb[0]) * nb[1]));
            bool near = false;
            for (int k = 0; k <= B && !near; ++k)
                for (int j = 0; j <= B && !near; ++j)
                    for (int i = 0; i <= B && !near; ++i)
                        near = std::fabs(d[at(bi * B + i, bj * B + j, bk * B + k)]) < band;
            if (near) {
                state[b] = 1;
                return;
            }
            Vec3 lo = s.origin + Vec3(bi * B, bj * B, bk * B) * s.voxelSize;
            Vec3 hi =
                s.origin + Vec3(std::min(bi * B + B, s.cells[0]), std::min(bj * B + B, s.cells[1]),
                                std::min(bk * B + B, s.cells[2])) *
                               s.voxelSize;
            state[b] = test.inside((lo + hi) * 0.5f) ? 3 : 2;
        });
    });
    // A vertex needs its own sign when any block holding it is within the band.
    auto blockOf = [&](int i, int j, int k) {
        return (static_cast<size_t>(k) * nb[1] + j) * nb[0] + i;
    };
    forEachVertex(s, threads, [&](int i, int j, int k, size_t idx, Vec3 p) {
        // The blocks holding vertex v along an axis: v / B, and v / B - 1 on a shared face.
        auto range = [&](int v, int n, int& lo, int& hi) {
            hi = std::min(v / B, n - 1);
            lo = v % B == 0 && v > 0 ? v / B - 1 : hi;
        };
        int bi0, bi1, bj0, bj1, bk0, bk1;
        range(i, nb[0], bi0, bi1);
        range(j, nb[1], bj0, bj1);
        range(k, nb[2], bk0, bk1);
        bool own = false;
        uint8_t any = 2;
        for (int bk = bk0; bk <= bk1; ++bk)
            for (int bj = bj0; bj <= bj1; ++bj)
                for (int bi = bi0; bi <= bi1; ++bi) {
                    uint8_t st = state[blockOf(bi, bj, bk)];
                    own |= st == 1;
                    any = st;
                }
        bool in = own ? test.inside(p) : any == 3;
        d[idx] = in ? -std::fabs(d[idx]) : std::fabs(d[idx]);
    });
}

}  // namespace sdft
