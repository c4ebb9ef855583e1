// The minimal OpenVDB program issue 15 compares `sdftrace render file.vdb` with, as a process:
// read the level set, cast one LevelSetRayIntersector ray per pixel (sdftrace's pinhole camera),
// headlight-shade the hit by the intersector's normal, write a binary PPM (the cheapest image
// file there is, in OpenVDB's favour).
//
//   sdftrace_openvdb_render file.vdb eye target up fov width height threads out.ppm
// eye, target, up: x,y,z. Prints "read X ms, render Y ms" on stderr.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/RayIntersector.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "sdftrace/math/camera.h"

using namespace sdft;

namespace {
Vec3 parse(const char* s) {
    Vec3 v;
    if (std::sscanf(s, "%f,%f,%f", &v.x, &v.y, &v.z) != 3) {
        std::fprintf(stderr, "expected x,y,z, got %s\n", s);
        std::exit(2);
    }
    return v;
}
}  // namespace

int main(int argc, char** argv) {
    if (argc != 10) {
        std::fprintf(stderr, "usage: %s file.vdb eye target up fov width height threads out.ppm\n",
                     argv[0]);
        return 2;
    }
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    openvdb::initialize();
    openvdb::io::File file(argv[1]);
    file.open(false);
    openvdb::FloatGrid::Ptr grid;
    for (auto it = file.beginName(); it != file.endName() && !grid; ++it)
        grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(it.gridName()));
    file.close();
    if (!grid) {
        std::fprintf(stderr, "%s: no float grid\n", argv[1]);
        return 1;
    }
    const auto t1 = Clock::now();
    CameraDesc cd;
    cd.eye = parse(argv[2]);
    cd.target = parse(argv[3]);
    cd.up = parse(argv[4]);
    cd.fovDeg = std::stof(argv[5]);
    cd.width = std::stoi(argv[6]);
    cd.height = std::stoi(argv[7]);
    const Camera cam(cd);
    std::vector<unsigned char> image(static_cast<size_t>(cd.width) * cd.height * 3, 0);
    using Isect = openvdb::tools::LevelSetRayIntersector<openvdb::FloatGrid>;
    tbb::enumerable_thread_specific<Isect> isect([&] { return Isect(*grid); });
    tbb::task_arena(std::stoi(argv[8])).execute([&] {
        tbb::parallel_for(0, cd.height, [&](int y) {
            for (int x = 0; x < cd.width; ++x) {
                const Ray r = cam.pixelRay(x, y);
                openvdb::math::Ray<double> ray(
                    openvdb::Vec3d(r.origin.x, r.origin.y, r.origin.z),
                    openvdb::Vec3d(r.direction.x, r.direction.y, r.direction.z));
                openvdb::Vec3d xyz(0.0), n(0.0);
                double t;
                if (!isect.local().intersectsWS(ray, xyz, n, t)) continue;
                n.normalize();
                const double shade = std::max(
                    0.0, -(n[0] * r.direction.x + n[1] * r.direction.y + n[2] * r.direction.z));
                const unsigned char v = static_cast<unsigned char>(255.0 * shade);
                unsigned char* px = &image[(static_cast<size_t>(y) * cd.width + x) * 3];
                px[0] = px[1] = px[2] = v;
            }
        });
    });
    const auto t2 = Clock::now();
    std::FILE* out = std::fopen(argv[9], "wb");
    if (!out) return 1;
    std::fprintf(out, "P6\n%d %d\n255\n", cd.width, cd.height);
    std::fwrite(image.data(), 1, image.size(), out);
    std::fclose(out);
    std::fprintf(stderr, "read %.1f ms, render %.1f ms\n",
                 std::chrono::duration<double, std::milli>(t1 - t0).count(),
                 std::chrono::duration<double, std::milli>(t2 - t1).count());
    return 0;
}
