#include "sdftrace/query/mesh_sampling.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "sdftrace/core/error.h"

namespace sdft {

namespace {

// SplitMix64 (Steele et al. 2014) over a counter: stream `k` of sample `i` under `seed`. Not the
// renderer's pcgHash (math/sampling.h): sample counts and seeds here go past 32 bits.
uint64_t mix(uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}
double uniform(uint64_t seed, uint64_t i, uint64_t k) {
    const uint64_t h = mix(mix(seed ^ mix(i)) + k);
    return static_cast<double>(h >> 11) * 0x1.0p-53;  // [0, 1)
}
// A standard normal pair by Box-Muller from streams k, k + 1.
std::array<double, 2> gaussian(uint64_t seed, uint64_t i, uint64_t k) {
    const double u1 = 1.0 - uniform(seed, i, k);  // (0, 1]
    const double u2 = uniform(seed, i, k + 1);
    const double r = std::sqrt(-2.0 * std::log(u1));
    return {r * std::cos(2 * M_PI * u2), r * std::sin(2 * M_PI * u2)};
}

// The running area of the faces: face f is drawn with probability area_f / total.
std::vector<double> areaPrefix(const MeshQuery& mesh) {
    const auto& v = mesh.vertices();
    const auto& f = mesh.faces();
    std::vector<double> prefix(f.size());
    double sum = 0;
    for (size_t i = 0; i < f.size(); ++i) {
        sum += 0.5 * norm(cross(v[f[i][1]] - v[f[i][0]], v[f[i][2]] - v[f[i][0]]));
        prefix[i] = sum;
    }
    if (!(sum > 0) || !std::isfinite(sum))
        throw InputError("sample: the mesh has no area to sample (every face is degenerate)");
    return prefix;
}

template <class Fn>
void forSamples(size_t n, Fn&& fn) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const auto& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) fn(i);
    });
}

// Surface sample i: a face by area (stream 0), a uniform point in it (streams 1, 2).
struct SurfacePoint {
    Vec3d point, normal;
    size_t face;
};
SurfacePoint surfacePoint(const MeshQuery& mesh, const std::vector<double>& prefix, uint64_t seed,
                          uint64_t i) {
    const double pick = uniform(seed, i, 0) * prefix.back();
    const size_t f = std::min<size_t>(
        std::upper_bound(prefix.begin(), prefix.end(), pick) - prefix.begin(), prefix.size() - 1);
    const auto& t = mesh.faces()[f];
    const Vec3d a = mesh.vertices()[t[0]], b = mesh.vertices()[t[1]], c = mesh.vertices()[t[2]];
    const double s = std::sqrt(uniform(seed, i, 1)), w = uniform(seed, i, 2);
    const Vec3d p = a * (1 - s) + b * (s * (1 - w)) + c * (s * w);
    const Vec3d n = cross(b - a, c - a);
    return {p, n * (1 / norm(n)), f};
}

}  // namespace

template <class T>
void sampleSurface(const MeshQuery& mesh, size_t n, uint64_t seed, T* points, T* normals,
                   int64_t* faces) {
    const std::vector<double> prefix = areaPrefix(mesh);
    forSamples(n, [&](size_t i) {
        const SurfacePoint s = surfacePoint(mesh, prefix, seed, i);
        for (int a = 0; a < 3; ++a) {
            if (points) points[3 * i + a] = static_cast<T>(s.point[a]);
            if (normals) normals[3 * i + a] = static_cast<T>(s.normal[a]);
        }
        if (faces) faces[i] = static_cast<int64_t>(s.face);
    });
}

template <class T>
void sampleNearSurface(const MeshQuery& mesh, size_t n, const std::vector<double>& sigmas,
                       uint64_t seed, T* points) {
    if (sigmas.empty()) throw InputError("sample_near_surface: sigmas: expected at least one");
    for (double s : sigmas)
        if (!std::isfinite(s) || s < 0)
            throw InputError("sample_near_surface: sigmas: " + std::to_string(s) +
                             " is not a finite width >= 0");
    const std::vector<double> prefix = areaPrefix(mesh);
    forSamples(n, [&](size_t i) {
        const SurfacePoint s = surfacePoint(mesh, prefix, seed, i);
        const double sigma = sigmas[i % sigmas.size()];
        const auto g01 = gaussian(seed, i, 3), g23 = gaussian(seed, i, 5);
        const Vec3d p = s.point + Vec3d{g01[0], g01[1], g23[0]} * sigma;
        for (int a = 0; a < 3; ++a) points[3 * i + a] = static_cast<T>(p[a]);
    });
}

template <class T>
void sampleVolume(size_t n, Vec3d lo, Vec3d hi, uint64_t seed, T* points) {
    forSamples(n, [&](size_t i) {
        for (int a = 0; a < 3; ++a)
            points[3 * i + a] = static_cast<T>(lo[a] + (hi[a] - lo[a]) * uniform(seed, i, a));
    });
}

std::vector<double> defaultNearSurfaceSigmas(const MeshQuery& mesh) {
    const double r = 0.5 * mesh.diagonal();
    return {0.05 * r, 0.0158 * r};
}

template void sampleSurface<float>(const MeshQuery&, size_t, uint64_t, float*, float*, int64_t*);
template void sampleSurface<double>(const MeshQuery&, size_t, uint64_t, double*, double*, int64_t*);
template void sampleNearSurface<float>(const MeshQuery&, size_t, const std::vector<double>&,
                                       uint64_t, float*);
template void sampleNearSurface<double>(const MeshQuery&, size_t, const std::vector<double>&,
                                        uint64_t, double*);
template void sampleVolume<float>(size_t, Vec3d, Vec3d, uint64_t, float*);
template void sampleVolume<double>(size_t, Vec3d, Vec3d, uint64_t, double*);

}  // namespace sdft
