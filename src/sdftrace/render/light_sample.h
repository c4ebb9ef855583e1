// Light geometry seen from a shading point: the direction to the light's centre and its falloff,
// the angle it subtends (the size of its penumbrae), and points on it for distributed shadow rays
// (Cook et al. 1984). GPU-ready.
#pragma once

#include <cmath>

#include "sdftrace/math/sampling.h"
#include "sdftrace/render/lighting.h"

namespace sdft {

struct LightDirection {
    Vec3 dir;         // unit, towards the light's centre
    float dist = 0;   // to the centre; +inf for directional lights
    float scale = 0;  // intensity reaching p (before the cosine at p)
};

SDFT_HOST_DEVICE inline LightDirection towardLight(const Light& light, Vec3 p) {
    LightDirection r;
    if (light.kind == Light::Kind::Directional) {
        r.dir = normalize(-light.direction);
        r.dist = INFINITY;
        r.scale = light.intensity;
        return r;
    }
    Vec3 d = light.position - p;
    r.dist = length(d);
    r.dir = d / std::fmax(r.dist, 1e-12f);
    r.scale = light.intensity / std::fmax(r.dist * r.dist, 1e-12f);
    if (light.kind == Light::Kind::Rect)
        r.scale *= std::fmax(0.0f, -dot(normalize(cross(light.u, light.v)), r.dir));
    return r;
}

// tan of the angular radius the light subtends at p: 0 for point lights and sunless directional
// ones. A rectangle counts as the disk of its area, foreshortened by the cosine at the light.
SDFT_HOST_DEVICE inline float lightTanRadius(const Light& light, Vec3 p) {
    switch (light.kind) {
        case Light::Kind::Directional:
            return std::tan(0.5f * light.angle);
        case Light::Kind::Point:
            return 0.0f;
        case Light::Kind::Sphere: {
            float d = length(light.position - p);
            if (d <= light.radius) return INFINITY;  // inside the light
            return light.radius / std::sqrt(d * d - light.radius * light.radius);
        }
        case Light::Kind::Rect: {
            Vec3 n = cross(light.u, light.v);
            float area = length(n);
            Vec3 to = light.position - p;
            float d = length(to);
            float cosL = std::fabs(dot(n / std::fmax(area, 1e-30f), to / std::fmax(d, 1e-30f)));
            return std::sqrt(area * cosL / kPi) / std::fmax(d, 1e-30f);
        }
    }
    return 0.0f;
}

struct LightSample {
    Vec3 dir;        // unit, from p
    float dist = 0;  // to the sampled point of the light; +inf for directional lights
};

// A point of the light seen from p for (u1, u2) in [0, 1)^2: spheres uniformly in the solid angle
// they subtend, rectangles uniformly in area, directional lights uniformly in their cone, points
// at the point.
SDFT_HOST_DEVICE inline LightSample sampleLight(const Light& light, Vec3 p, float u1, float u2) {
    LightSample s;
    switch (light.kind) {
        case Light::Kind::Directional:
            s.dir = light.angle > 0 ? sampleCone(normalize(-light.direction),
                                                 std::cos(0.5f * light.angle), u1, u2)
                                    : normalize(-light.direction);
            s.dist = INFINITY;
            return s;
        case Light::Kind::Point: {
            Vec3 d = light.position - p;
            s.dist = length(d);
            s.dir = d / std::fmax(s.dist, 1e-12f);
            return s;
        }
        case Light::Kind::Sphere: {
            Vec3 d = light.position - p;
            float dc = length(d);
            Vec3 axis = d / std::fmax(dc, 1e-12f);
            if (dc <= light.radius) {  // inside the light: nothing can shadow it
                s.dir = axis;
                s.dist = 0;
                return s;
            }
            float sinMax = light.radius / dc;
            float cosMax = std::sqrt(std::fmax(0.0f, 1.0f - sinMax * sinMax));
            s.dir = sampleCone(axis, cosMax, u1, u2);
            // The near intersection with the sphere along s.dir.
            float b = dot(s.dir, d);
            float disc = std::fmax(0.0f, b * b - (dc * dc - light.radius * light.radius));
            s.dist = std::fmax(0.0f, b - std::sqrt(disc));
            return s;
        }
        case Light::Kind::Rect: {
            Vec3 q = light.position + light.u * (u1 - 0.5f) + light.v * (u2 - 0.5f);
            Vec3 d = q - p;
            s.dist = length(d);
            s.dir = d / std::fmax(s.dist, 1e-12f);
            return s;
        }
    }
    return s;
}

}  // namespace sdft
