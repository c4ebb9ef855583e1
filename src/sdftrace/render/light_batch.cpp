#include "sdftrace/render/light_batch.h"

#include <immintrin.h>

#include "sdftrace/core/macros.h"
#include "sdftrace/exec/simd.h"

namespace sdft {

namespace {

// lightTerm of a directional light for one hit.
inline void addOne(const Light& light, const PixelMaterial& m, Vec3 n, Vec3 d, float visible,
                   Vec3& radiance) {
    radiance += direct_pixel::lightTerm(light, m, Vec3(0.0f), n, d, visible);
}

#if SDFT_HAVE_AVX2_DISPATCH

constexpr int kLanes = 8;
using F8 = float __attribute__((vector_size(kLanes * sizeof(float)), aligned(32)));
using I8 = int32_t __attribute__((vector_size(kLanes * sizeof(int32_t)), aligned(32)));

// specularPower (lighting.h) on eight lanes: by squaring where every lane has the same whole
// exponent in range (raiseBySquaring's products in its order), else lane by lane.
SDFT_TARGET_AVX2 inline F8 specularPower8(F8 x, F8 e) {
    bool same = true;
    for (int l = 1; l < kLanes; ++l) same &= e[l] == e[0];
    if (same && squaredExponent(e[0])) return raiseBySquaring(x, static_cast<int>(e[0]));
    F8 out;
    for (int l = 0; l < kLanes; ++l) out[l] = specularPower(x[l], e[l]);
    return out;
}

// Eight hits' Vec3s as three vectors of x, y and z.
SDFT_TARGET_AVX2 inline void load3(const Vec3* v, F8 out[3]) {
    static_assert(sizeof(Vec3) == 3 * sizeof(float), "Vec3s are read as packed floats");
    const __m256i index = _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21);
    const float* base = &v[0].x;
    for (int a = 0; a < 3; ++a) out[a] = (F8)_mm256_i32gather_ps(base + a, index, 4);
}

SDFT_TARGET_AVX2 void addDirectionalAvx2(const Light& light, const PixelMaterial* materials,
                                         bool shared, const Vec3* normals, const Vec3* views,
                                         const float* visible, int n, Vec3* radiance) {
    const LightDirection to = towardLight(light, Vec3(0.0f));
    const Vec3 l = to.dir;
    F8 c[3], kd, ks, e;
    auto loadMaterials = [&](int h) {  // hits h .. h + 7 (or materials[0] if shared)
        for (int k = 0; k < kLanes; ++k) {
            const PixelMaterial& m = materials[shared ? 0 : h + k];
            for (int a = 0; a < 3; ++a) c[a][k] = m.color[a];
            kd[k] = m.diffuse;
            ks[k] = m.specular;
            e[k] = m.shininess;
        }
    };
    if (shared && n >= kLanes) loadMaterials(0);
    int h = 0;
    for (; h + kLanes <= n; h += kLanes) {
        F8 nv[3], dv[3], rad[3];
        load3(normals + h, nv);
        load3(views + h, dv);
        F8 vis;
        __builtin_memcpy(&vis, visible + h, sizeof vis);
        // lightTerm: nothing where the light is hidden or below the horizon.
        const F8 ndl = nv[0] * l.x + nv[1] * l.y + nv[2] * l.z;
        const I8 lit = (vis != 0.0f) & ~(ndl <= 0.0f);
        if (!_mm256_movemask_ps((__m256)lit)) continue;
        if (!shared) loadMaterials(h);
        // blinnPhong: the half vector normalised as normalize() does, the lobe, the sum.
        F8 hv[3] = {l.x - dv[0], l.y - dv[1], l.z - dv[2]};
        const F8 len = (F8)_mm256_sqrt_ps((__m256)(hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]));
        const F8 inv = 1.0f / len;
        for (int a = 0; a < 3; ++a) hv[a] = len > 0.0f ? hv[a] * inv : F8{};
        const F8 ndh = nv[0] * hv[0] + nv[1] * hv[1] + nv[2] * hv[2];
        // std::fmax(ndh, 0): 0 where ndh is NaN.
        const F8 x = (F8)_mm256_max_ps((__m256)ndh, _mm256_setzero_ps());
        const F8 spec = ks * specularPower8(x, e);
        const F8 lambert = kd * ndl, share = to.scale * vis;
        load3(radiance + h, rad);
        for (int a = 0; a < 3; ++a) {
            const F8 term = (c[a] * lambert + spec) * light.color[a] * share;
            rad[a] = lit ? rad[a] + term : rad[a];
        }
        for (int k = 0; k < kLanes; ++k) radiance[h + k] = Vec3(rad[0][k], rad[1][k], rad[2][k]);
    }
    for (; h < n; ++h)
        addOne(light, materials[shared ? 0 : h], normals[h], views[h], visible[h], radiance[h]);
}

#endif  // SDFT_HAVE_AVX2_DISPATCH

}  // namespace

void addDirectionalLight(const Light& light, const PixelMaterial* materials, bool shared,
                         const Vec3* normals, const Vec3* views, const float* visible, int n,
                         Vec3* radiance) {
#if SDFT_HAVE_AVX2_DISPATCH
    if (useAvx2()) {
        addDirectionalAvx2(light, materials, shared, normals, views, visible, n, radiance);
        return;
    }
#endif
    for (int h = 0; h < n; ++h)
        addOne(light, materials[shared ? 0 : h], normals[h], views[h], visible[h], radiance[h]);
}

}  // namespace sdft
