// sdftrace.write_image and sdftrace.srgb: numpy images to PNG / EXR / PFM through the library's
// writers (atomic; PNG colour tone-mapped to sRGB, scalar PNGs as heat maps with a legend), so
// examples need no imaging package.
#include <algorithm>
#include <string>
#include <vector>

#include "bindings.h"
#include "sdftrace/core/error.h"
#include "sdftrace/io/image_io.h"

namespace sdft::py {

namespace {

void writeImage(const pyb::handle& pathArg, const pyb::handle& image, const std::string& label) {
    const std::string path = pathArgument(pathArg);
    const ImageFormat format = imageFormatFromPath(path, "write_image: path");
    pyb::array a = pyb::array::ensure(image);
    if (!a) {
        PyErr_Clear();
        throw InputError("write_image: image: expected an H x W or H x W x C array");
    }
    if (a.ndim() != 2 && a.ndim() != 3)
        throw InputError("write_image: image: expected an H x W or H x W x C array, got " +
                         std::to_string(a.ndim()) + " dimensions");
    const int h = static_cast<int>(a.shape(0)), w = static_cast<int>(a.shape(1));
    const int c = a.ndim() == 3 ? static_cast<int>(a.shape(2)) : 1;
    if (c != 1 && c != 3)
        throw InputError("write_image: image: " + std::to_string(c) +
                         " channels; expected 1 (scalar) or 3 (RGB)");
    if (w < 1 || h < 1) throw InputError("write_image: image: empty");
    const size_t n = static_cast<size_t>(w) * h * c;
    if (a.dtype().is(pyb::dtype::of<uint8_t>())) {
        if (format != ImageFormat::Png)
            throw InputError("write_image: " + path +
                             ": 8-bit images are written as .png; give float data for .exr/.pfm");
        auto bytes = pyb::array_t<uint8_t, pyb::array::c_style | pyb::array::forcecast>::ensure(a);
        std::vector<unsigned char> data(bytes.data(), bytes.data() + n);
        if (c == 1) {  // grey to RGB
            std::vector<unsigned char> rgb(3 * data.size());
            for (size_t i = 0; i < data.size(); ++i)
                rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = data[i];
            data.swap(rgb);
        }
        pyb::gil_scoped_release release;
        writePng(path, w, h, 3, data);
        return;
    }
    FloatArray f = FloatArray::ensure(a);
    if (!f) {
        PyErr_Clear();
        throw InputError("write_image: image: expected numbers");
    }
    std::vector<float> data(f.data(), f.data() + n);
    pyb::gil_scoped_release release;
    if (format == ImageFormat::Exr) {
        writeExr(path, w, h, c, data,
                 c == 3 ? std::vector<std::string>{"R", "G", "B"}
                        : std::vector<std::string>{label.empty() ? "Y" : label});
    } else if (format == ImageFormat::Pfm) {
        writePfm(path, w, h, c, data);
    } else if (c == 3) {
        writePng(path, w, h, 3, toneMapSrgb(data));
    } else {
        int outHeight = 0;
        const auto rgb = heatMapWithLegend(data, w, h, label, outHeight);
        writePng(path, w, outHeight, 3, rgb);
    }
}

}  // namespace

void bindImages(pyb::module_& m) {
    m.def("write_image", &writeImage, pyb::arg("path"), pyb::arg("image"), pyb::arg("label") = "",
          "Writes `image`, an H x W x 3 (RGB) or H x W (scalar) array, to `path` by its "
          "extension: .png (float RGB: linear, "
          "tone-mapped to sRGB; uint8: as is; scalar float: a heat map with a legend named "
          "`label`), .exr or .pfm (32-bit float). Atomic: a temporary file renamed into place.");
    m.def(
        "srgb",
        [](const pyb::handle& color) {
            FloatArray f = FloatArray::ensure(color);
            if (!f || f.ndim() != 3 || f.shape(2) != 3) {
                PyErr_Clear();
                throw InputError("srgb: color: expected an H x W x 3 array of linear radiance");
            }
            std::vector<float> data(f.data(), f.data() + f.size());
            const auto bytes = toneMapSrgb(data);
            pyb::array_t<uint8_t> out(std::vector<pyb::ssize_t>{f.shape(0), f.shape(1), 3});
            std::copy(bytes.begin(), bytes.end(), out.mutable_data());
            return out;
        },
        pyb::arg("color"),
        "Linear radiance `color` (H x W x 3) to 8-bit sRGB, as PNG output tone-maps it");
}

}  // namespace sdft::py
