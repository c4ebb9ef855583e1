#!/usr/bin/env python3
"""Writes the seed inputs of the mesh_<format> fuzz targets (fuzz/mesh_file_fuzz.cpp) into
fuzz/corpus/mesh_<format>/: a cube and a tetrahedron in every variant of each format family
(PLY ascii, binary little- and big-endian with extra properties and elements; STL binary and
ascii; OFF and COFF with quads; OBJ with v/vt/vn corners, negative indices and groups; glTF with a
data URI and GLB; for mesh_anim, glTF with a moving node and with a morph target), each under
4 KB (libFuzzer's default input length). Run once; libFuzzer's merged corpora grow from them.

    python3 fuzz/make_mesh_seeds.py
"""
import base64
import json
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))

CUBE_V = [(x, y, z) for z in (-1.0, 1.0) for y in (-1.0, 1.0) for x in (-1.0, 1.0)]
CUBE_Q = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
TET_V = [(1.0, 1.0, 1.0), (-1.0, -1.0, 1.0), (-1.0, 1.0, -1.0), (1.0, -1.0, -1.0)]
TET_F = [(0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2)]


def tris(faces):
    return [(f[0], f[j - 1], f[j]) for f in faces for j in range(2, len(f))]


def ply(v, f, fmt, vtype="float", ltypes="uchar int", extra=True):
    head = "ply\nformat %s 1.0\ncomment seed\n" % fmt
    head += "element vertex %d\n" % len(v)
    head += "".join("property %s %s\n" % (vtype, a) for a in "xyz")
    if extra:
        head += "property uchar red\n"
    head += "element face %d\nproperty list %s vertex_indices\n" % (len(f), ltypes)
    if extra:
        head += "element edge 1\nproperty int vertex1\nproperty int vertex2\n"
    head += "end_header\n"
    if fmt == "ascii":
        body = "".join("%g %g %g%s\n" % (p + (" 9" if extra else "",)) for p in v)
        body += "".join("%d %s\n" % (len(q), " ".join(map(str, q))) for q in f)
        if extra:
            body += "0 1\n"
        return head.encode() + body.encode()
    e = "<" if fmt == "binary_little_endian" else ">"
    vc = {"float": "f", "double": "d", "int": "i", "short": "h"}[vtype]
    ct, it = [{"uchar": "B", "int": "i", "uint": "I", "ushort": "H"}[t] for t in ltypes.split()]
    body = b"".join(struct.pack(e + "3" + vc + ("B" if extra else ""), *(p + ((9,) if extra else ())))
                    for p in v)
    body += b"".join(struct.pack(e + ct + it * len(q), len(q), *q) for q in f)
    if extra:
        body += struct.pack(e + "ii", 0, 1)
    return head.encode() + body


def stl_binary(v, f):
    out = b"solid but binary".ljust(80, b" ") + struct.pack("<I", len(f))
    for t in f:
        out += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *v[i]) for i in t) + b"\0\0"
    return out


def stl_ascii(v, f):
    s = "solid seed\n"
    for t in f:
        s += " facet normal 0 0 0\n  outer loop\n"
        s += "".join("   vertex %g %g %g\n" % v[i] for i in t)
        s += "  endloop\n endfacet\n"
    return (s + "endsolid seed\n").encode()


def off(v, f, magic="OFF"):
    s = "%s\n# seed\n%d %d 0\n" % (magic, len(v), len(f))
    s += "".join("%g %g %g%s\n" % (p + (" 1 0 0 1" if magic == "COFF" else "",)) for p in v)
    s += "".join("%d %s\n" % (len(q), " ".join(map(str, q))) for q in f)
    return s.encode()


def obj(v, f, style):
    s = "# seed\nmtllib none.mtl\no seed\n" + "".join("v %g %g %g\n" % p for p in v)
    if style == "corners":
        s += "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\ng faces\nusemtl m\n"
        s += "".join("f %s\n" % " ".join("%d/%d/1" % (i + 1, k % 3 + 1) for k, i in enumerate(q))
                     for q in f)
    elif style == "negative":
        n = len(v)
        s += "".join("f %s\n" % " ".join(str(i - n) for i in q) for q in f)
    else:
        s += "".join("f %s\n" % " ".join(str(i + 1) for i in q) for q in f)
    return s.encode()


def gltf_parts(v, f):
    pos = b"".join(struct.pack("<3f", *p) for p in v)
    idx = b"".join(struct.pack("<3H", *t) for t in f)
    idx += b"\0" * ((4 - len(idx) % 4) % 4)
    buf = pos + idx
    lo = [min(p[a] for p in v) for a in range(3)]
    hi = [max(p[a] for p in v) for a in range(3)]
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"mesh": 0, "translation": [0.5, 0, 0]}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
           "buffers": [{"byteLength": len(buf)}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
                           {"buffer": 0, "byteOffset": len(pos), "byteLength": 6 * len(f)}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(v),
                          "type": "VEC3", "min": lo, "max": hi},
                         {"bufferView": 1, "componentType": 5123, "count": 3 * len(f),
                          "type": "SCALAR"}]}
    return doc, buf


def gltf(v, f):
    doc, buf = gltf_parts(v, f)
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(buf).decode()
    return json.dumps(doc).encode()


def glb(v, f):
    doc, buf = gltf_parts(v, f)
    j = json.dumps(doc).encode()
    j += b" " * ((4 - len(j) % 4) % 4)
    total = 12 + 8 + len(j) + 8 + len(buf)
    return (struct.pack("<III", 0x46546C67, 2, total) + struct.pack("<II", len(j), 0x4E4F534A) + j
            + struct.pack("<II", len(buf), 0x004E4942) + buf)


def gltf_animated(v, f, kind):
    """A glTF whose node moves (kind "node": translation keys) or whose mesh morphs (kind "morph":
    one target, weight keys): the mesh_anim target's seeds."""
    doc, buf = gltf_parts(v, f)
    buf += b"\0" * ((4 - len(buf) % 4) % 4)
    views, accessors = doc["bufferViews"], doc["accessors"]

    def add(data, count, typ, extra=None):
        nonlocal buf
        views.append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(data)})
        acc = {"bufferView": len(views) - 1, "componentType": 5126, "count": count, "type": typ}
        acc.update(extra or {})
        accessors.append(acc)
        buf += data
        return len(accessors) - 1

    times = add(struct.pack("<3f", 0, 0.5, 1), 3, "SCALAR", {"min": [0], "max": [1]})
    if kind == "node":
        out = add(struct.pack("<9f", 0, 0, 0, 0, 1, 0, 0, 0, 1), 3, "VEC3")
        channel = {"sampler": 0, "target": {"node": 0, "path": "translation"}}
    else:
        delta = [(0.0, 0.5 * p[1], 0.0) for p in v]
        target = add(b"".join(struct.pack("<3f", *d) for d in delta), len(v), "VEC3",
                     {"min": [0, min(d[1] for d in delta), 0], "max": [0, max(d[1] for d in delta), 0]})
        doc["meshes"][0]["primitives"][0]["targets"] = [{"POSITION": target}]
        doc["meshes"][0]["weights"] = [0]
        out = add(struct.pack("<3f", 0, 1, 0), 3, "SCALAR")
        channel = {"sampler": 0, "target": {"node": 0, "path": "weights"}}
    doc["animations"] = [{"name": kind, "channels": [channel],
                          "samplers": [{"input": times, "output": out, "interpolation": "LINEAR"}]}]
    doc["buffers"][0] = {"byteLength": len(buf),
                         "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}
    return json.dumps(doc).encode()


def main():
    seeds = {}
    for name, v, q in (("cube", CUBE_V, CUBE_Q), ("tet", TET_V, TET_F)):
        t = tris(q)
        seeds.setdefault("ply", {}).update({
            name + "-ascii.ply": ply(v, q, "ascii"),
            name + "-little.ply": ply(v, q, "binary_little_endian"),
            name + "-big-double.ply": ply(v, q, "binary_big_endian", "double", "uchar uint"),
            name + "-plain.ply": ply(v, t, "binary_little_endian", extra=False),
        })
        seeds.setdefault("stl", {}).update({name + "-binary.stl": stl_binary(v, t),
                                            name + "-ascii.stl": stl_ascii(v, t)})
        seeds.setdefault("off", {}).update({name + ".off": off(v, q),
                                            name + "-colour.off": off(v, q, "COFF")})
        seeds.setdefault("obj", {}).update({name + ".obj": obj(v, q, "plain"),
                                            name + "-corners.obj": obj(v, q, "corners"),
                                            name + "-negative.obj": obj(v, q, "negative")})
        seeds.setdefault("gltf", {}).update({name + ".gltf": gltf(v, t), name + ".glb": glb(v, t)})
        seeds.setdefault("anim", {}).update({name + "-node.gltf": gltf_animated(v, t, "node"),
                                             name + "-morph.gltf": gltf_animated(v, t, "morph")})
    for family, files in seeds.items():
        d = os.path.join(HERE, "corpus", "mesh_" + family)
        os.makedirs(d, exist_ok=True)
        for name, data in files.items():
            assert len(data) <= 4096, name
            with open(os.path.join(d, "seed-" + name), "wb") as out:
                out.write(data)


if __name__ == "__main__":
    main()
