#include "sdftrace/bake/texture_coords.h"

#include <tbb/combinable.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "sdftrace/exec/thread_arena.h"

namespace sdft {

void helperFrame(Vec3 axis, Vec3& e1, Vec3& e2) {
    const Vec3 a = normalize(axis);
    const Vec3 ref = std::fabs(a.x) < 0.9f ? Vec3(1, 0, 0) : Vec3(0, 0, 1);
    e1 = normalize(ref - a * dot(ref, a));
    e2 = cross(a, e1);
}

namespace {

// The helper surface: a sphere or a capped cylinder around `center` enclosing the grid.
struct Helper {
    TexcoordKind kind;
    Vec3 c, a, e1, e2;
    float radius = 0, h0 = 0, h1 = 1;

    // Negative inside, positive outside (a signed measure, not a distance for the cylinder's caps).
    float g(Vec3 p) const {
        const Vec3 r = p - c;
        if (kind == TexcoordKind::Sphere) return length(r) - radius;
        const float h = dot(r, a);
        const float radial = length(r - a * h);
        return std::max({radial - radius, h0 - h, h - h1});
    }
    // The stored vector of a point on (or projected to) the helper.
    Vec3 encode(Vec3 p) const {
        const Vec3 r = p - c;
        if (kind == TexcoordKind::Sphere) {
            const float len = length(r);
            const Vec3 d = len > 0 ? r / len : a;
            return {dot(d, e1), dot(d, e2), dot(d, a)};
        }
        const float h = dot(r, a);
        const Vec3 radial = r - a * h;
        const float len = length(radial);
        const Vec3 d = len > 0 ? radial / len : e1;
        return {dot(d, e1), dot(d, e2), std::clamp((h - h0) / (h1 - h0), 0.0f, 1.0f)};
    }
    // Leaving direction where the field has no gradient: away from the centre (or the axis).
    Vec3 outward(Vec3 p) const {
        Vec3 r = p - c;
        if (kind == TexcoordKind::Cylinder) r = r - a * dot(r, a);
        return length(r) > 0 ? normalize(r) : e1;
    }
};

// The box of the surface's crossings of the grid's edges (linear interpolation along each edge
// whose samples change sign): tighter than the surface cells' box, which is off by up to a voxel.
Bounds3 crossingBounds(const Grid& grid) {
    const GridShape& shape = grid.shape();
    const GridView view = grid.view();
    Bounds3 box;  // empty
    auto edges = [&](const float* s, int nx, int ny, int nz, Vec3 origin) {
        const size_t stride[3] = {1, static_cast<size_t>(nx), static_cast<size_t>(nx) * ny};
        for (int k = 0; k < nz; ++k)
            for (int j = 0; j < ny; ++j)
                for (int i = 0; i < nx; ++i) {
                    const int at[3] = {i, j, k};
                    const size_t idx = i + stride[1] * j + stride[2] * k;
                    for (int a = 0; a < 3; ++a) {
                        if (at[a] + 1 >= (a == 0 ? nx : a == 1 ? ny : nz)) continue;
                        const float f0 = s[idx], f1 = s[idx + stride[a]];
                        if ((f0 < 0) == (f1 < 0)) continue;
                        Vec3 p = origin + Vec3(i, j, k) * shape.voxelSize;
                        p[a] += f0 / (f0 - f1) * shape.voxelSize;
                        box.include(p);
                    }
                }
    };
    if (grid.kind() == GridKind::Dense) {
        edges(grid.samples().data(), shape.cells[0] + 1, shape.cells[1] + 1, shape.cells[2] + 1,
              shape.origin);
    } else {
        const int B = grid.blockSize(), V = B + 1;
        grid.forEachPagedBlock(
            [&](int bi, int bj, int bk, size_t slot) {
                const int32_t data = view.blockData[slot];
                if (data < 0) return;
                float samples[9 * 9 * 9];  // (B+1)^3, B <= 8
                grid.expandBlock(data, samples);
                edges(samples, V, V, V,
                      shape.origin + Vec3(bi * B, bj * B, bk * B) * shape.voxelSize);
            },
            false);
    }
    return box;
}

Helper makeHelper(const Grid& grid, const TexcoordOptions& o) {
    Helper h;
    h.kind = o.helper;
    h.a = normalize(o.axis);
    helperFrame(h.a, h.e1, h.e2);
    const Bounds3 all = grid.shape().bounds();
    Bounds3 surface = crossingBounds(grid);
    if (surface.empty()) surface = all;
    h.c = o.autoCenter ? (surface.lo + surface.hi) * 0.5f : o.center;
    // Enclose every sample: the particles start inside the helper.
    float radius = 0, lo = INFINITY, hi = -INFINITY;
    for (int n = 0; n < 8; ++n) {
        const Vec3 corner((n & 1) ? all.hi.x : all.lo.x, (n & 2) ? all.hi.y : all.lo.y,
                          (n & 4) ? all.hi.z : all.lo.z);
        const Vec3 r = corner - h.c;
        const float along = dot(r, h.a);
        radius =
            std::max(radius, h.kind == TexcoordKind::Sphere ? length(r) : length(r - h.a * along));
        lo = std::min(lo, along);
        hi = std::max(hi, along);
    }
    const float margin = grid.shape().voxelSize;
    h.radius = radius + margin;
    h.h0 = lo - margin;
    h.h1 = hi + margin;
    return h;
}

}  // namespace

const char* texcoordKindName(TexcoordKind kind) {
    switch (kind) {
        case TexcoordKind::Sphere:
            return "sphere";
        case TexcoordKind::Cylinder:
            return "cylinder";
        default:
            return "none";
    }
}

bool parseTexcoordKind(const std::string& s, TexcoordKind& out) {
    for (TexcoordKind k : {TexcoordKind::Sphere, TexcoordKind::Cylinder})
        if (s == texcoordKindName(k)) return out = k, true;
    return false;
}

namespace {

// Counters of one thread's particles.
struct ParticleCounts {
    size_t particles = 0, projected = 0, unfinished = 0, ridges = 0, atLevel = 0;
    double steps = 0, evaluations = 0;
    void add(const ParticleCounts& o) {
        particles += o.particles, projected += o.projected, unfinished += o.unfinished;
        ridges += o.ridges, atLevel += o.atLevel, steps += o.steps, evaluations += o.evaluations;
    }
};

// Liktor §5.5.2: one particle per sample, carried along the field's gradient to the helper
// surface, where its position gives the texture coordinates.
struct ParticleTracer {
    const Helper& helper;
    const std::function<float(Vec3)>& field;
    const TexcoordOptions& o;
    float voxel;

    // The unit gradient at p by central differences (the helper's outward direction where it
    // vanishes).
    Vec3 direction(Vec3 p, ParticleCounts& c) const {
        const float h = voxel;
        const Vec3 g(field(p + Vec3(h, 0, 0)) - field(p - Vec3(h, 0, 0)),
                     field(p + Vec3(0, h, 0)) - field(p - Vec3(0, h, 0)),
                     field(p + Vec3(0, 0, h)) - field(p - Vec3(0, 0, h)));
        c.evaluations += 6;
        const float len = length(g);
        return len > 1e-12f ? g / len : helper.outward(p);
    }

    // Where the particle from x stops: on the helper, at the stop level, or on a ridge.
    Vec3 trace(Vec3 x, ParticleCounts& c) const {
        ++c.particles;
        int step = 0;
        float f = field(x);  // the traced field (a scene's may differ from the sample by L)
        c.evaluations += 1;
        for (; step < o.maxSteps; ++step) {
            // Larger steps far from the surface, where the field lines straighten.
            const float s = std::clamp(0.5f * std::fabs(f), 0.5f * voxel, helper.radius / 8);
            const Vec3 d1 = direction(x, c);
            const Vec3 d2 = direction(x + d1 * (0.5f * s), c);  // midpoint (RK2)
            const Vec3 next = x + d2 * s;
            const float g0 = helper.g(x), g1 = helper.g(next);
            if (g1 >= 0) {
                // Where the segment leaves the helper.
                const float t = g0 < g1 ? std::clamp(g0 / (g0 - g1), 0.0f, 1.0f) : 1.0f;
                x = x + (next - x) * t;
                break;
            }
            const float fNext = field(next);
            c.evaluations += 1;
            if (fNext >= o.stopLevel) {
                // Where the segment reaches the level (continuous in the start point, unlike
                // stopping at a whole step).
                const float t =
                    fNext > f ? std::clamp((o.stopLevel - f) / (fNext - f), 0.0f, 1.0f) : 0.0f;
                x = x + (next - x) * t;
                ++c.atLevel;
                break;
            }
            x = next;
            // No ascent: the particle sits on a ridge or plateau of the field (a medial surface,
            // or the constant region a narrow band leaves), where the gradient stops leading
            // outward. From here it goes straight out (radial projection).
            if (!(fNext > f)) {
                ++c.ridges;
                break;
            }
            f = fNext;
        }
        c.steps += step + 1;
        if (step == o.maxSteps) ++c.unfinished;
        return x;
    }
};

// f(position, sample value, index of the stored sample) for every stored sample, in parallel.
template <class F>
void forEachStoredSample(const Grid& grid, F&& f) {
    const GridShape& shape = grid.shape();
    const float voxel = shape.voxelSize;
    if (grid.kind() == GridKind::Dense) {
        const int nx = shape.cells[0] + 1, ny = shape.cells[1] + 1;
        tbb::parallel_for(0, shape.cells[2] + 1, [&](int k) {
            for (int j = 0; j < ny; ++j)
                for (int i = 0; i < nx; ++i) {
                    const size_t idx = (static_cast<size_t>(k) * ny + j) * nx + i;
                    f(shape.origin + Vec3(i, j, k) * voxel, grid.samples()[idx], idx);
                }
        });
        return;
    }
    // Each stored sample at the vertex it was taken from (the shared constant blocks' samples
    // have none and keep zero vectors: no cell that changes sign reads them).
    std::vector<std::array<int, 3>> blockOf(grid.surfaceBlockCount());
    grid.forEachPagedBlock([&](int bi, int bj, int bk, size_t slot) {
        const int32_t data = grid.blockData()[slot];
        if (data >= 0) blockOf[static_cast<size_t>(data)] = {bi, bj, bk};
    });
    const int B = grid.blockSize();
    grid.forEachStoredSample([&](size_t idx, int32_t block, int x, int y, int z) {
        const auto& b = blockOf[static_cast<size_t>(block)];
        const Vec3 p = shape.origin + Vec3(b[0] * B + x, b[1] * B + y, b[2] * B + z) * voxel;
        f(p, grid.blockSamples()[idx], idx);
    });
}

}  // namespace

TexcoordStats bakeTexcoords(Grid& grid, const std::function<float(Vec3)>& field,
                            const TexcoordOptions& o) {
    const Helper helper = makeHelper(grid, o);
    const float voxel = grid.shape().voxelSize, band = o.bandVoxels * voxel;
    std::vector<float> out(3 * grid.storedSamples());
    const ParticleTracer tracer{helper, field, o, voxel};
    tbb::combinable<ParticleCounts> counts;
    ThreadArena arena(o.threads);
    arena.execute([&] {
        forEachStoredSample(grid, [&](Vec3 x, float f0, size_t idx) {
            ParticleCounts& c = counts.local();
            Vec3 q = x;
            if (std::fabs(f0) > band) {
                ++c.projected;  // beyond the band: radial projection from the sample
            } else {
                q = tracer.trace(x, c);
            }
            const Vec3 e = helper.encode(q);
            out[3 * idx] = e.x, out[3 * idx + 1] = e.y, out[3 * idx + 2] = e.z;
        });
    });
    ParticleCounts total;
    counts.combine_each([&](const ParticleCounts& c) { total.add(c); });
    TexcoordStats st;
    st.particles = total.particles;
    st.projected = total.projected;
    st.unfinished = total.unfinished;
    st.ridges = total.ridges;
    st.atLevel = total.atLevel;
    st.meanSteps = total.particles ? total.steps / total.particles : 0;
    st.fieldEvaluations = total.particles ? total.evaluations / total.particles : 0;
    st.center = helper.c;
    st.radius = helper.radius;
    grid.setTexcoords(o.helper, std::move(out), "texture coordinates");
    return st;
}

}  // namespace sdft
