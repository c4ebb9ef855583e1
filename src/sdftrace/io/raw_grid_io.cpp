#include "sdftrace/io/raw_grid_io.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <vector>

#include "dense_shape.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/atomic_file.h"

namespace sdft {

namespace {

constexpr const char* kFormat = "sdftrace-raw-float32";

struct Sidecar {
    int64_t dims[3];
    double origin[3];
    double voxelSize;
};

Sidecar readSidecar(const std::string& path) {
    std::ifstream in(path);
    if (!in)
        throw InputError(path + ": cannot open the sidecar of the raw grid (a raw grid needs " +
                         "PATH.json beside it: docs/file-formats.md)");
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception&) {
        throw InputError(path + ": malformed JSON");
    }
    auto fail = [&](const std::string& key, const std::string& accepted) {
        throw InputError(path + ": /" + key + ": " + accepted);
    };
    if (!j.is_object()) fail("", "expected an object with format, dims, origin, voxel_size");
    for (const auto& [key, value] : j.items())
        if (key != "format" && key != "dims" && key != "origin" && key != "voxel_size")
            fail(key, "unknown key (accepted: format, dims, origin, voxel_size)");
    if (!j.contains("format") || j["format"] != kFormat)
        fail("format", std::string("expected \"") + kFormat + "\"");
    Sidecar s{};
    auto triple = [&](const char* key, auto* out, bool integer) {
        if (!j.contains(key) || !j[key].is_array() || j[key].size() != 3)
            fail(key, "expected an array of three numbers");
        for (int a = 0; a < 3; ++a) {
            const auto& v = j[key][a];
            if (integer ? !v.is_number_integer() : !v.is_number())
                fail(std::string(key) + "/" + std::to_string(a),
                     integer ? "expected an integer" : "expected a number");
            out[a] = v.template get<std::remove_pointer_t<decltype(out)>>();
        }
    };
    triple("dims", s.dims, true);
    triple("origin", s.origin, false);
    if (!j.contains("voxel_size") || !j["voxel_size"].is_number())
        fail("voxel_size", "expected a number");
    s.voxelSize = j["voxel_size"].get<double>();
    return s;
}

}  // namespace

std::string rawSidecarPath(const std::string& rawPath) { return rawPath + ".json"; }

Grid loadRawGrid(const std::string& path) {
    const std::string sidecarPath = rawSidecarPath(path);
    const Sidecar sc = readSidecar(sidecarPath);
    const GridShape shape = io_detail::denseShape(sc.dims, sc.origin, sc.voxelSize, sidecarPath);
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(path, ec);
    if (ec) throw InputError(path + ": cannot open the raw grid (does it exist?)");
    const uint64_t want = shape.vertexCount() * sizeof(float);
    if (bytes != want) {
        throw InputError(path + ": " + std::to_string(bytes) + " bytes, but the sidecar's dims " +
                         std::to_string(sc.dims[0]) + "x" + std::to_string(sc.dims[1]) + "x" +
                         std::to_string(sc.dims[2]) + " need " + std::to_string(want) +
                         " (float32 samples, no header)");
    }
    std::vector<float> samples(shape.vertexCount());
    std::ifstream in(path, std::ios::binary);
    if (!in ||
        !in.read(reinterpret_cast<char*>(samples.data()), static_cast<std::streamsize>(want)))
        throw InputError(path + ": cannot read the raw grid");
    for (size_t i = 0; i < samples.size(); ++i)
        if (!std::isfinite(samples[i]))
            throw InputError(path + ": non-finite sample at index " + std::to_string(i));
    return Grid::dense(shape, std::move(samples));
}

void saveRawGrid(const Grid& grid, const std::string& path) {
    const GridShape& s = grid.shape();
    const std::vector<float> samples = grid.vertexSamples();
    nlohmann::json j = {{"format", kFormat},
                        {"dims", {s.vertices(0), s.vertices(1), s.vertices(2)}},
                        {"origin", {s.origin.x, s.origin.y, s.origin.z}},
                        {"voxel_size", s.voxelSize}};
    writeFileAtomically(path, samples.data(), samples.size() * sizeof(float));
    const std::string text = j.dump(2) + "\n";
    writeFileAtomically(rawSidecarPath(path), text.data(), text.size());
}

}  // namespace sdft
