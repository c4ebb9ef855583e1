// Meshes whose signed distance is known in closed form, for the bake tests: a box, an icosphere
// (within its tessellation gap of the unit sphere) and a torus.
#pragma once

#include <array>
#include <cmath>
#include <map>

#include "sdftrace/bake/triangle_mesh.h"

namespace sdft::testing {

inline TriangleMesh boxMesh(Vec3 h) {
    TriangleMesh m;
    for (int i = 0; i < 8; ++i)
        m.positions.push_back({(i & 1) ? h.x : -h.x, (i & 2) ? h.y : -h.y, (i & 4) ? h.z : -h.z});
    // Outward winding, two triangles per face.
    m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                   {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    return m;
}

// An icosahedron subdivided `levels` times, vertices pushed onto the unit sphere.
inline TriangleMesh icosphere(int levels) {
    const float t = 1.618034f;
    TriangleMesh m;
    for (Vec3 v : {Vec3(-1, t, 0), Vec3(1, t, 0), Vec3(-1, -t, 0), Vec3(1, -t, 0), Vec3(0, -1, t),
                   Vec3(0, 1, t), Vec3(0, -1, -t), Vec3(0, 1, -t), Vec3(t, 0, -1), Vec3(t, 0, 1),
                   Vec3(-t, 0, -1), Vec3(-t, 0, 1)})
        m.positions.push_back(normalize(v));
    m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            auto key = std::make_pair(std::min(a, b), std::max(a, b));
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            m.positions.push_back(normalize(m.positions[a] + m.positions[b]));
            return mid[key] = static_cast<uint32_t>(m.positions.size() - 1);
        };
        std::vector<std::array<uint32_t, 3>> next;
        for (auto [a, b, c] : m.triangles) {
            uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
        }
        m.triangles = next;
    }
    return m;
}

// A torus around z (major radius R, minor r) as a closed u x v quad grid, each quad split in two,
// outward winding.
inline TriangleMesh torusMesh(float R, float r, int nu, int nv) {
    TriangleMesh m;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            float u = 6.2831853f * i / nu, v = 6.2831853f * j / nv;
            m.positions.push_back({(R + r * std::cos(v)) * std::cos(u),
                                   (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
        }
    auto at = [&](int i, int j) { return static_cast<uint32_t>((i % nu) * nv + (j % nv)); };
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    return m;
}

// The largest distance between the torus mesh and the smooth torus: the sagitta of the chords
// around both circles (a bound on how far the polyhedron strays from the surface).
inline float torusTessellationGap(float R, float r, int nu, int nv) {
    float du = kPi / nu, dv = kPi / nv;
    return (R + r) * (1 - std::cos(du)) + r * (1 - std::cos(dv));
}

}  // namespace sdft::testing
