#include "sdftrace/render/shadow_map.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>

#include "sdftrace/core/memory_budget.h"
#include "sdftrace/math/sampling.h"
#include "sdftrace/trace/field_tracer.h"

namespace sdft {

namespace {

float chebyshev(float mean, float meanSq, float t, float minVariance) {
    if (t <= mean) return 1.0f;
    const float variance = std::max(meanSq - mean * mean, minVariance);
    const float d = t - mean;
    return variance / (variance + d * d);
}

// Separable box filter of radius r over a w x w image of 4-channel texels (clamped edges). Each
// window is summed afresh: a running sum would lose the small moments next to the huge ones of
// far texels (exp(40) squared) to cancellation.
void boxFilter(float* img, int w, int r) {
    if (r <= 0) return;
    std::vector<float> tmp(4 * static_cast<size_t>(w) * w);
    const float inv = 1.0f / (2 * r + 1);
    for (int pass = 0; pass < 2; ++pass) {
        const float* src = pass == 0 ? img : tmp.data();
        float* dst = pass == 0 ? tmp.data() : img;
        tbb::parallel_for(0, w, [&](int line) {
            auto index = [&](int i) {
                i = std::clamp(i, 0, w - 1);
                return pass == 0 ? size_t(line) * w + i : size_t(i) * w + line;
            };
            for (int i = 0; i < w; ++i) {
                float sum[4] = {0, 0, 0, 0};
                for (int k = i - r; k <= i + r; ++k)
                    for (int c = 0; c < 4; ++c) sum[c] += src[4 * index(k) + c];
                for (int c = 0; c < 4; ++c) dst[4 * index(i) + c] = sum[c] * inv;
            }
        });
    }
}

}  // namespace

ShadowMap::ShadowMap(const Tape& tape, const Light& light, const Bounds3& region,
                     const TraceOptions& trace, ShadowMapFilter filter, const ShadowMapOptions& o)
    : m_filter(filter), m_o(o) {
    SDFT_CHECK(region.finite() && !region.empty() && o.resolution > 0);
    const Vec3 centre = region.center();
    const float radius = std::max(0.5f * length(region.extent()), 1e-6f);
    m_ortho = light.kind == Light::Kind::Directional;
    const float tMax =
        m_ortho ? orthographicFaces(tape, light, centre, radius) : cubeFaces(light, centre, radius);
    traceDepths(tape, trace, tMax);
    if (m_filter == ShadowMapFilter::Evsm) buildMoments();
}

// A square map over the region's bounding sphere; rays start beyond the scene's bounds (or the
// sphere) on the light's side, so occluders outside the region still cast.
float ShadowMap::orthographicFaces(const Tape& tape, const Light& light, Vec3 centre,
                                   float radius) {
    m_res = m_o.resolution;
    Face f;
    f.forward = normalize(light.direction);
    orthonormalBasis(f.forward, f.right, f.up);
    m_faces.push_back(f);
    m_extent = 2 * radius;
    float start = -radius;
    const Bounds3 all = tape.bounds();
    if (all.finite()) {
        for (int c = 0; c < 8; ++c) {
            Vec3 q((c & 1) ? all.hi.x : all.lo.x, (c & 2) ? all.hi.y : all.lo.y,
                   (c & 4) ? all.hi.z : all.lo.z);
            start = std::min(start, dot(q - centre, f.forward));
        }
    }
    start -= 1e-3f * radius;
    m_origin = centre + f.forward * start - f.right * radius - f.up * radius;
    m_near = dot(centre, f.forward) - radius;
    m_far = dot(centre, f.forward) + radius;
    return radius - start;
}

// Six axis-aligned 90-degree faces: face k looks along +-axis k/2.
float ShadowMap::cubeFaces(const Light& light, Vec3 centre, float radius) {
    m_res = std::max(1, m_o.resolution / 2);
    m_origin = light.position;
    for (int k = 0; k < 6; ++k) {
        const int axis = k / 2;
        Face f;
        f.forward = Vec3(0.0f);
        f.forward[axis] = (k & 1) ? -1.0f : 1.0f;
        f.right = Vec3(0.0f);
        f.right[axis == 0 ? 1 : 0] = 1.0f;
        f.up = Vec3(0.0f);
        f.up[axis == 2 ? 1 : 2] = 1.0f;
        m_faces.push_back(f);
    }
    m_near = 0;
    m_far = length(centre - light.position) + radius;
    return m_far;
}

void ShadowMap::traceDepths(const Tape& tape, const TraceOptions& trace, float tMax) {
    const size_t perFace = static_cast<size_t>(m_res) * m_res;
    const TraceOptions opts = trace.secondary();
    // Depths, and for EVSM four moments and their filtered copy per texel.
    checkMemoryBudget(static_cast<double>(perFace * m_faces.size()) * sizeof(float) *
                          (m_filter == ShadowMapFilter::Evsm ? 9 : 1),
                      "shadow_map_resolution " + std::to_string(m_o.resolution),
                      "a shadow map of " + std::to_string(m_faces.size()) + " face(s) of " +
                          std::to_string(m_res) + "x" + std::to_string(m_res) + " texels",
                      "use a lower shadow-map resolution");
    m_depth.assign(perFace * m_faces.size(), INFINITY);
    std::atomic<uint64_t> evaluations{0};
    tbb::enumerable_thread_specific<PacketScratch> scratch;
    const int rows = m_res * static_cast<int>(m_faces.size());
    tbb::parallel_for(0, rows, [&](int row) {
        const int face = row / m_res, j = row % m_res;
        const Face& f = m_faces[face];
        std::vector<RaySegment> seg(m_res);
        std::vector<TraceResult> res(m_res);
        for (int i = 0; i < m_res; ++i) {
            Ray ray;
            if (m_ortho) {
                ray = {m_origin + f.right * ((i + 0.5f) * m_extent / m_res) +
                           f.up * ((j + 0.5f) * m_extent / m_res),
                       f.forward};
            } else {
                const float x = 2.0f * (i + 0.5f) / m_res - 1.0f;
                const float y = 2.0f * (j + 0.5f) / m_res - 1.0f;
                ray = {m_origin, normalize(f.forward + f.right * x + f.up * y)};
            }
            seg[i] = {ray, 0.0f, tMax};
        }
        tracePacket(tape, seg, opts, res, scratch.local());
        uint64_t e = 0;
        for (int i = 0; i < m_res; ++i) {
            e += res[i].evaluations;
            if (!res[i].hit) continue;
            const Vec3 hit = seg[i].ray.at(res[i].t);
            m_depth[face * perFace + size_t(j) * m_res + i] =
                m_ortho ? dot(hit, f.forward) : length(hit - m_origin);
        }
        evaluations += e;
    });
    m_evaluations = evaluations.load();
}

void ShadowMap::buildMoments() {
    const size_t perFace = static_cast<size_t>(m_res) * m_res;
    m_moments.resize(4 * m_depth.size());
    for (size_t t = 0; t < m_depth.size(); ++t) {
        const float z = std::isfinite(m_depth[t])
                            ? std::clamp((m_depth[t] - m_near) / (m_far - m_near), 0.0f, 1.0f)
                            : 1.0f;
        const float w = 2 * z - 1;
        const float pos = std::exp(m_o.evsmPositive * w), neg = -std::exp(-m_o.evsmNegative * w);
        m_moments[4 * t + 0] = pos;
        m_moments[4 * t + 1] = pos * pos;
        m_moments[4 * t + 2] = neg;
        m_moments[4 * t + 3] = neg * neg;
    }
    for (size_t face = 0; face < m_faces.size(); ++face)
        boxFilter(m_moments.data() + 4 * face * perFace, m_res, m_o.evsmRadius);
}

bool ShadowMap::project(Vec3 p, int& face, float& x, float& y, float& depth, float& texel) const {
    const Vec3 q = p - m_origin;
    if (m_ortho) {
        const Face& f = m_faces[0];
        face = 0;
        x = dot(q, f.right) / m_extent * m_res;
        y = dot(q, f.up) / m_extent * m_res;
        depth = dot(p, f.forward);
        texel = m_extent / m_res;
    } else {
        const Vec3 a(std::fabs(q.x), std::fabs(q.y), std::fabs(q.z));
        const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
        face = 2 * axis + (q[axis] < 0 ? 1 : 0);
        const Face& f = m_faces[face];
        const float z = dot(q, f.forward);
        if (z <= 0) return false;
        x = (dot(q, f.right) / z + 1.0f) * 0.5f * m_res;
        y = (dot(q, f.up) / z + 1.0f) * 0.5f * m_res;
        x = std::clamp(x, 0.0f, std::nextafter(static_cast<float>(m_res), 0.0f));
        y = std::clamp(y, 0.0f, std::nextafter(static_cast<float>(m_res), 0.0f));
        depth = length(q);
        texel = 2.0f * depth / m_res;
    }
    return x >= 0 && y >= 0 && x < m_res && y < m_res;
}

float ShadowMap::pcf(int face, float x, float y, float depth, float bias) const {
    const int ci = static_cast<int>(x), cj = static_cast<int>(y), r = m_o.pcfRadius;
    const float* map = m_depth.data() + static_cast<size_t>(face) * m_res * m_res;
    int lit = 0, taps = 0;
    for (int j = cj - r; j <= cj + r; ++j)
        for (int i = ci - r; i <= ci + r; ++i) {
            ++taps;
            if (i < 0 || j < 0 || i >= m_res || j >= m_res) {
                // Off a cube face: the nearest texel of this face; off the ortho map: lit.
                if (m_ortho) {
                    ++lit;
                    continue;
                }
            }
            const int ii = std::clamp(i, 0, m_res - 1), jj = std::clamp(j, 0, m_res - 1);
            lit += depth <= map[size_t(jj) * m_res + ii] + bias;
        }
    return static_cast<float>(lit) / static_cast<float>(taps);
}

float ShadowMap::evsm(int face, float x, float y, float depth) const {
    // Bilinear moments around (x, y).
    const float* moments = m_moments.data() + 4 * static_cast<size_t>(face) * m_res * m_res;
    const float fx = x - 0.5f, fy = y - 0.5f;
    const int i0 = static_cast<int>(std::floor(fx)), j0 = static_cast<int>(std::floor(fy));
    const float ax = fx - i0, ay = fy - j0;
    float m[4] = {0, 0, 0, 0};
    for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di) {
            const int i = std::clamp(i0 + di, 0, m_res - 1), j = std::clamp(j0 + dj, 0, m_res - 1);
            const float w = (di ? ax : 1 - ax) * (dj ? ay : 1 - ay);
            for (int c = 0; c < 4; ++c) m[c] += w * moments[4 * (size_t(j) * m_res + i) + c];
        }
    const float z = std::clamp((depth - m_near) / (m_far - m_near), 0.0f, 1.0f);
    const float w = 2 * z - 1;
    const float pos = std::exp(m_o.evsmPositive * w), neg = -std::exp(-m_o.evsmNegative * w);
    // Variance floors: a depth step of 1e-4 of the range through each warp's slope.
    const float dPos = m_o.evsmPositive * pos * 2e-4f, dNeg = m_o.evsmNegative * neg * 2e-4f;
    const float v =
        std::min(chebyshev(m[0], m[1], pos, dPos * dPos), chebyshev(m[2], m[3], neg, dNeg * dNeg));
    const float a = m_o.bleedReduction;
    return std::clamp((v - a) / (1 - a), 0.0f, 1.0f);
}

float ShadowMap::visibility(Vec3 p, Vec3 n) const {
    int face;
    float x, y, depth, texel;
    if (!project(p, face, x, y, depth, texel)) return 1.0f;
    // Normal offset by `bias` texels, then project again.
    if (!project(p + n * (m_o.bias * texel), face, x, y, depth, texel)) return 1.0f;
    return m_filter == ShadowMapFilter::Pcf ? pcf(face, x, y, depth, m_o.bias * texel)
                                            : evsm(face, x, y, depth);
}

}  // namespace sdft
